"""The native C layer's headers (prandtl_fmu/fmu/native/*.h) name one another without a circle: read from the C
text (comments and strings stripped, nothing compiled), a header names another when it includes it or uses a
name that the other defines and it does not (a function it calls, a type, a macro, a struct, an enum constant or
a global; of the headers that define it, the nearest its includes reach, else all: a kind's Instance), and that
graph has no circle. A kind's function that a shared header runs is named only from above: a prototype declares,
it does not define, so a prototype in a shared header and the call after it name the kind's header that defines
the function.

The nodes are the headers of the folder (the vendor's FMI 3.0 headers under fmi3/ aside); ``scene.h``, generated
per build, and the FMI fronts ``fmi2.c`` and ``fmi3.c`` are the build's configuration around them, not nodes: a
word only they define (FMI, FMU_STATE, ...) makes no edge, and no header calls a function only they define.
"""
import functools
import re
from pathlib import Path

from tests.paths import ROOT

NATIVE = ROOT / "prandtl_fmu" / "fmu" / "native"

_LEXEMES = re.compile(r'"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'|/\*.*?\*/|//[^\n]*', re.S)
_IDENTIFIER = re.compile(r"[A-Za-z_]\w*")
_KEYWORDS = {"struct", "union", "enum", "typedef", "static", "const", "volatile", "return", "sizeof", "if", "else",
             "for", "while", "do", "switch", "case", "default", "break", "continue", "goto", "void", "int", "char",
             "double", "float", "long", "short", "unsigned", "signed", "extern", "inline", "defined"}


def _strip(text: str):
    """``text`` without comments and line continuations, and the same with every string and character literal
    emptied (the includes are read from the first)."""
    def comment(match):
        lexeme = match.group(0)
        return lexeme if lexeme[0] in "\"'" else " " + "\n" * lexeme.count("\n")
    bare = _LEXEMES.sub(comment, text).replace("\\\n", " ")
    return bare, _LEXEMES.sub(lambda match: match.group(0)[0] * 2, bare)


def _blank_blocks(code: str):
    """``code`` with the inside of every brace block blanked (the top level left), and the blocks' texts."""
    top, blocks, depth, start = [], [], 0, 0
    for index, char in enumerate(code):
        if char == "{":
            if depth == 0:
                start = index + 1
            depth += 1
        elif char == "}":
            depth -= 1
            if depth == 0:
                blocks.append((start, code[start:index]))
        top.append(char if depth == 0 or char == "{" and depth == 1 else " ")
    return "".join(top), blocks


@functools.lru_cache(maxsize=None)
def read_header(path: Path):
    """(includes, defined, functions, uses) of one C file: the local headers it includes; the names it defines
    (functions with a body, macros, typedefs, struct/union/enum tags, enum constants, globals; a prototype only
    declares); which of those are functions; every name it uses (not a member: after ``.`` or ``->``, or declared
    in a struct), with whether it is called somewhere (followed by ``(``)."""
    bare, code = _strip(path.read_text())
    includes = set(re.findall(r'^\s*#\s*include\s*"([^"]+)"', bare, re.M))
    directives = re.findall(r"^\s*#.*$", code, re.M)
    body = re.sub(r"^\s*#.*$", " ", code, flags=re.M)
    top, blocks = _blank_blocks(body)
    functions = set(re.findall(r"\b(\w+)\s*\((?:[^()]|\([^()]*\))*\)\s*\{", top)) - _KEYWORDS
    defined = functions | {name for line in directives for name in re.findall(r"^\s*#\s*define\s+(\w+)", line)}
    defined |= set(re.findall(r"\b(?:struct|union|enum)\s+(\w+)\s*\{", top))
    declarations = re.sub(r"(?:[\w*]+\s+|\*\s*)*\w+\s*\((?:[^()]|\([^()]*\))*\)\s*\{\s*\}", ";", top)
    for statement in declarations.split(";"):
        statement = statement.strip()
        typedef = statement.startswith("typedef")
        if not (typedef or "=" in statement or statement and "(" not in statement):
            continue  # a prototype
        declarator = statement.split("}")[-1] if typedef else statement.split("=")[0]
        pointer = re.search(r"\(\s*\*[\w\s]*?(\w+)\s*\)", declarator)  # (*name): a pointer to a function
        names = _IDENTIFIER.findall(re.sub(r"\[[^\]]*\]", " ", declarator))
        if pointer or names:
            defined.add(pointer.group(1) if pointer else names[-1])
    inside, members = dict(blocks), []
    for match in re.finditer(r"\b(struct|union|enum)\b[\s\w]*\{", top):
        text = inside[match.end()]
        if match.group(1) == "enum":
            defined |= {item.split("=")[0].strip() for item in text.split(",") if item.strip()}
        else:  # a member's name: before ``[``, ``;``, ``,``, ``:`` or the ``)`` of a pointer to a function
            members += [(match.end() + m.start(), match.end() + m.end()) for m in
                        re.finditer(r"\w+(?=\s*[\[;,:)])", text)]
    for begin, stop in reversed(members):
        body = body[:begin] + " " * (stop - begin) + body[stop:]
    uses = {}
    for line in directives:
        if re.match(r"^\s*#\s*include", line):
            continue
        defining = re.match(r"^\s*#\s*define\s+\w+(?:\(([^)]*)\))?", line)
        parameters = set(_IDENTIFIER.findall(defining.group(1) or "")) if defining else set()
        _collect(line[defining.end():] if defining else line, uses, parameters)
    _collect(body, uses, set())
    return includes, defined - _KEYWORDS, functions, uses


def _collect(text: str, uses: dict, skip: set):
    """Every identifier of ``text`` not after ``.`` or ``->`` (a member) into ``uses``: name -> called somewhere."""
    for match in re.finditer(r"(?<![\w.])(?<!->)([A-Za-z_]\w*)(\s*\()?", text):
        name = match.group(1)
        if name not in _KEYWORDS and name not in skip:
            uses[name] = uses.get(name, False) or bool(match.group(2))


@functools.lru_cache(maxsize=None)
def naming_graph(folder: Path):
    """{header: {named header: [why, ...]}} over the headers of ``folder``: it includes the named header, or uses a
    name it does not define and the named one does: the nearest its includes reach, else every one that defines
    it (a kind's Instance: each kind's types header). A function is named where it is called: a local variable of the
    same name is not the function."""
    headers = {path.name: read_header(path) for path in sorted(folder.glob("*.h"))}
    definers = {}
    for name, (_, defined, _, _) in headers.items():
        for symbol in defined:
            definers.setdefault(symbol, set()).add(name)
    graph = {name: {} for name in headers}
    for name, (includes, defined, _, uses) in headers.items():
        distance, queue = {name: 0}, [name]  # the headers its includes reach, how many includes away
        for header in queue:
            for included in sorted(headers[header][0] & set(headers)):
                if included not in distance:
                    distance[included] = distance[header] + 1
                    queue.append(included)
        for included in sorted(includes & set(headers)):
            graph[name].setdefault(included, []).append("#include")
        for symbol, called in sorted(uses.items()):
            if symbol in defined or symbol not in definers:
                continue
            if not called and any(symbol in headers[other][2] for other in definers[symbol]):
                continue
            near = [other for other in definers[symbol] if other in distance]
            meant = {other for other in near if distance[other] == min(distance[o] for o in near)} or definers[symbol]
            for other in sorted(meant):
                graph[name].setdefault(other, []).append(symbol)
    return graph


def circles(graph: dict):
    """The shortest circle through each header that is in one, each circle once: [[a, ..., a], ...]."""
    reach = {}
    for start in graph:
        seen, todo = set(), [start]
        while todo:
            for other in graph[todo.pop()]:
                if other not in seen:
                    seen.add(other)
                    todo.append(other)
        reach[start] = seen
    found, seen = [], set()
    for start in sorted(graph):
        if start in reach[start]:
            group = {other for other in reach[start] if start in reach[other]}
            circle = _circle_through(graph, start, group)
            edges = frozenset(zip(circle, circle[1:]))
            if edges not in seen:
                seen.add(edges)
                found.append(circle)
    return found


def _circle_through(graph: dict, start: str, group: set):
    """A shortest circle from ``start`` back to it inside ``group`` (breadth first)."""
    back, queue = {}, [start]
    for node in queue:
        for other in sorted(graph[node]):
            if other == start:
                chain = []
                while node != start:
                    chain.append(node)
                    node = back[node]
                return [start] + chain[::-1] + [start]
            if other in group and other not in back:
                back[other] = node
                queue.append(other)
    raise AssertionError(f"{start} is in no circle")


def explain(graph: dict, found: list) -> str:
    """Each circle, and why each header in it names the next."""
    lines = []
    for circle in found:
        lines.append(" -> ".join(circle))
        for a, b in zip(circle, circle[1:]):
            lines.append(f"    {a} names {b}: {', '.join(sorted(set(graph[a][b]))[:8])}")
    return "\n".join(lines)


def test_no_circle_among_the_native_headers():
    graph = naming_graph(NATIVE)
    found = circles(graph)
    assert found == [], "the native headers name one another in a circle:\n" + explain(graph, found)


def test_no_header_calls_a_function_of_the_fmi_fronts():
    """The FMI fronts (fmi2.c, fmi3.c) are above every header: a header that declared a function only they define
    and called it would name them from below (the words they define for the headers, FMI, FMU_STATE, ..., are the
    build's configuration, as scene.h's are)."""
    headers = {path.name: read_header(path) for path in sorted(NATIVE.glob("*.h"))}
    in_headers = set().union(*(defined for _, defined, _, _ in headers.values()))
    fronts = {path.name: read_header(path)[2] - in_headers for path in sorted(NATIVE.glob("*.c"))}
    upward = [f"{name} calls {symbol} ({front})" for name, (_, _, _, uses) in headers.items()
              for symbol, called in sorted(uses.items()) for front, functions in fronts.items()
              if called and symbol in functions]
    assert upward == [], "the FMI fronts named from below:\n" + "\n".join(upward)


def test_the_reader_sees_includes_calls_types_and_macros():
    """The reader itself, on the headers: an include, a call of a function another header defines, a type and a
    macro of another header, and a hook the kind defines that the layer above the kinds calls."""
    graph = naming_graph(NATIVE)
    assert "#include" in graph["element.h"]["core.h"]
    assert "instantiated" in graph["element.h"]["core.h"]  # a call
    assert "Instance" in graph["core.h"]["element_types.h"]  # a type
    assert "COPY_FIELD" in graph["element_types.h"]["common.h"]  # a macro, in a macro's body
    assert "initialize" in graph["machine.h"]["element.h"]  # a hook, called from above


def test_a_hook_declared_below_and_defined_above_is_a_circle(tmp_path):
    """The circle this test exists for: a shared header that declares a hook and calls it, included by the kind's
    header that defines the hook."""
    (tmp_path / "shared.h").write_text('/* "kind.h" */\nstatic int hook(int x);\n'
                                       'static int run(void) { return hook(1); }\n')
    (tmp_path / "kind.h").write_text('#include "shared.h"\nstatic int hook(int x) { return x; } // hook(\n')
    graph = naming_graph(tmp_path)
    assert graph == {"kind.h": {"shared.h": ["#include"]}, "shared.h": {"kind.h": ["hook"]}}
    assert circles(graph) == [["kind.h", "shared.h", "kind.h"]]

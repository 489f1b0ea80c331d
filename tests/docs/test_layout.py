"""The package's layout shows its architecture: read from the sources' import statements (``ast``, nothing is
imported), the graph of the modules of prandtl_fmu that import one another has no circle, and no module imports
one of a higher layer (the layers below, also written in ``prandtl_fmu/__init__.py``); every module says in its
first lines (its docstring) what it holds.

Every import counts: at module level and inside functions (a function-level import is a dependency all the
same, only a deferred one), relative imports resolved, and ``import a.b.c`` also runs ``a/__init__.py`` and
``a/b/__init__.py`` (a package's __init__ that imports its submodules drags them in with any of them).
"""
import ast
import functools
import re

from tests.paths import ROOT

PACKAGE = ROOT / "prandtl_fmu"

# Bottom to top: a module may import its own layer and those below. Names are relative to prandtl_fmu; a name
# covers its submodules ("kernels" is every kernels.*), the longest name that matches decides; "" is the
# package's __init__ alone (it imports nothing at load: its public names resolve on first use), and so is
# "network", the network package's __init__.
LAYERS = [
    ("base: compiled-code helpers and tools every layer may use",
     ["", "network", "_jit", "catalog", "compiling", "libm", "noise", "outputs", "resources", "saved_state"]),
    ("loads and effects with memory, in their compiled form",
     ["loads", "memory", "memory.dahl", "memory.delay", "memory.history"]),
    ("kernels: compiled building blocks of the steps",
     ["kernels", "network.kernels", "network.chain"]),
    ("steppers: one module per scheme", ["steppers"]),
    ("scenes: what is simulated, read and checked",
     ["schema", "effects", "masing", "scene_tables", "scene", "stability", "network.model"]),
    ("a run's parts: a scene compiled for the kernels, a stretch of steps and its bookkeeping",
     ["compiled", "stepping"]),
    ("the stepped objects, and the network's own driver",
     ["element", "connector", "network.driver"]),
    ("the batch driver and the summaries of runs", ["driver", "summary"]),
    ("the FMUs of both runtimes", ["fmu"]),
    ("tools built on the library", ["sweep", "identify", "plots", "bench", "frequency"]),
    ("the command line", ["cli", "__main__"]),
]

# Imports that break the rules, each with its reason and what removes it: (importer, imported module as named
# in the import statement). Keep this list short; an entry that is no longer needed fails the test.
KNOWN_EXCEPTIONS = {
}


@functools.lru_cache(maxsize=None)
def module_files():
    """Dotted name relative to prandtl_fmu ("" for the package itself) -> (path, is_package)."""
    modules = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        if is_package:
            parts = parts[:-1]
        modules[".".join(parts)] = (path, is_package)
    return modules


@functools.lru_cache(maxsize=None)
def _tree(path):
    return ast.parse(path.read_text(), str(path))


def _absolute(name: str):
    """``name`` (dotted, absolute) relative to prandtl_fmu, or None if it is not ours."""
    if name == "prandtl_fmu":
        return ""
    if name.startswith("prandtl_fmu."):
        return name[len("prandtl_fmu."):]
    return None


def _join(*parts):
    return ".".join(part for part in parts if part)


def _ours(name: str, modules):
    """The module of ours that ``name`` names (a module, or an attribute of one: its module)."""
    while name not in modules:
        if "." not in name:
            return None if name else ""
        name = name.rsplit(".", 1)[0]
    return name


def _with_packages(target: str, importer: str):
    """``target`` and the packages whose __init__ importing it runs, but those the importer is inside of."""
    found = [target]
    parts = target.split(".")
    for cut in range(1, len(parts)):
        package = ".".join(parts[:cut])
        if not (importer == package or importer.startswith(package + ".")):
            found.append(package)
    return found


@functools.lru_cache(maxsize=None)
def import_graph():
    """{(importer, imported): [(line, imported module as named in the statement), ...]} over every import of
    every module of prandtl_fmu."""
    modules = module_files()
    edges = {}
    for name, (path, is_package) in modules.items():
        package = name if is_package else (name.rsplit(".", 1)[0] if "." in name else "")
        for node in ast.walk(_tree(path)):
            named = []
            if isinstance(node, ast.Import):
                named = [_absolute(alias.name) for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".") if package else []
                    base = base[:len(base) - (node.level - 1)] if node.level > 1 else base
                    source = _join(".".join(base), node.module or "")
                else:
                    source = _absolute(node.module)
                if source is not None:
                    # "from . import kernels" names a submodule; "from .scene import Scene" an attribute
                    named = [_join(source, alias.name) if _join(source, alias.name) in modules else source
                             for alias in node.names]
            for target in named:
                target = _ours(target, modules) if target is not None else None
                if target is None or target == name:
                    continue
                for reached in _with_packages(target, name):
                    if reached != name:
                        edges.setdefault((name, reached), set()).add((node.lineno, target))
    return modules, {edge: sorted(imports) for edge, imports in edges.items()}


def _layer(name: str) -> int:
    best, level = None, None
    for index, (_, names) in enumerate(LAYERS):
        for covered in names:
            if name == covered or (covered and name.startswith(covered + ".")):
                if best is None or len(covered) > len(best):
                    best, level = covered, index
    return level


@functools.lru_cache(maxsize=None)
def ruled_edges():
    """The import graph without the known exceptions (an edge every one of whose imports is excepted drops
    out), and the exceptions in use."""
    modules, edges = import_graph()
    kept, used = {}, set()
    for (importer, reached), imports in edges.items():
        left = []
        for line, named in imports:
            if (importer, named) in KNOWN_EXCEPTIONS:
                used.add((importer, named))
            else:
                left.append((line, named))
        if left:
            kept[(importer, reached)] = left
    return modules, kept, used


def _cycles(nodes, edges):
    """The strongly connected components of more than one module (Tarjan), each with one circle through it."""
    successors = {node: sorted({b for (a, b) in edges if a == node}) for node in nodes}
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in successors[node]:
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            component = []
            while True:
                other = stack.pop()
                on_stack.discard(other)
                component.append(other)
                if other == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(nodes):
        if node not in index:
            visit(node)
    circles = []
    for component in found:
        inside = set(component)
        start, path, seen = component[0], [component[0]], {component[0]: 0}
        while True:  # walk inside the component until a module repeats: that stretch is a circle
            step = next(other for other in successors[path[-1]] if other in inside)
            if step in seen:
                circles.append(path[seen[step]:] + [step])
                break
            seen[step] = len(path)
            path.append(step)
    return circles


def _where(modules, importer, imports):
    path = modules[importer][0].relative_to(PACKAGE.parent)
    return ", ".join(f"{path}:{line} ({named})" for line, named in imports)


def test_every_module_has_a_layer():
    modules = module_files()
    assert [name or "prandtl_fmu" for name in modules if _layer(name) is None] == [], \
        "add these modules to LAYERS in tests/docs/test_layout.py (and to the list in prandtl_fmu/__init__.py)"
    stale = [covered for _, names in LAYERS for covered in names
             if not any(name == covered or (covered and name.startswith(covered + ".")) for name in modules)]
    assert stale == [], f"LAYERS names modules that do not exist: {stale}"


def test_no_import_circle():
    modules, edges, _ = ruled_edges()
    circles = _cycles(modules, edges)
    lines = []
    for circle in circles:
        lines.append(" -> ".join(name or "prandtl_fmu" for name in circle))
        for importer, reached in zip(circle, circle[1:]):
            lines.append(f"    {_where(modules, importer, edges[(importer, reached)])}")
    assert circles == [], "import circles:\n" + "\n".join(lines)


def test_no_module_imports_a_higher_layer():
    modules, edges, _ = ruled_edges()
    upward = []
    for (importer, reached), imports in sorted(edges.items()):
        if _layer(reached) > _layer(importer):
            upward.append(f"{importer or 'prandtl_fmu'} (layer {_layer(importer)}) imports {reached} (layer "
                          f"{_layer(reached)}): {_where(modules, importer, imports)}")
    assert upward == [], "imports from a lower layer into a higher one:\n" + "\n".join(upward)


def test_known_exceptions_are_still_needed():
    _, _, used = ruled_edges()
    assert sorted(set(KNOWN_EXCEPTIONS) - used) == [], "remove these from KNOWN_EXCEPTIONS: no such import is left"


def test_the_package_docstring_lists_the_layers():
    """The layers of this test are the ones prandtl_fmu/__init__.py writes down ("1. what: ``a``, ``b``", one
    numbered item a layer, bottom to top)."""
    text = ast.get_docstring(ast.parse((PACKAGE / "__init__.py").read_text()))
    items = []
    for line in text.splitlines():
        if re.match(r"\d+\. ", line):
            items.append(line)
        elif items and line.startswith("   ") and line.strip():
            items[-1] += " " + line.strip()
    written = [["" if name == "__init__" else name for name in re.findall(r"``([^`]+)``", item.split(":", 1)[1])]
               for item in items]
    assert written == [names for _, names in LAYERS]


def test_every_module_says_what_it_holds():
    """Every module and package __init__ opens with a docstring (its first lines say what it holds)."""
    missing = []
    for name, (path, _) in module_files().items():
        docstring = ast.get_docstring(_tree(path))
        if not docstring or not docstring.strip():
            missing.append(str(path.relative_to(PACKAGE.parent)))
    assert missing == [], f"modules without a docstring: {missing}"


def test_the_graph_reader_sees_every_kind_of_import():
    """The reader of the import statements itself: a relative import at two levels, a submodule named in a
    from-import, a function-level import and the package __init__ that importing a submodule runs."""
    _, edges = import_graph()
    assert ("driver", "network.driver") in edges  # function-level: simulate hands a network scene over
    assert ("sweep", "sweep.runs") in edges  # from .runs import ... in a package's __init__
    assert ("steppers.exact", "steppers.exact_series") in edges  # from . import exact_series
    assert ("fmu.description", "") in edges  # from .. import __version__
    assert ("compiled", "memory") in edges  # from .memory import compile_memory
    assert ("stepping", "memory.dahl") in edges and ("stepping", "memory") in edges  # a submodule, and its package
    assert ("bench.lockstep", "kernels") in edges  # importing kernels.stack runs kernels/__init__.py

"""Where the test suite's compile time goes: the logs the suite writes under PRANDTL_FMU_COMPILE_LOG.

    NUMBA_CACHE_DIR=$(mktemp -d) PRANDTL_FMU_COMPILE_LOG=out/compiles python -m pytest -q
    python benchmarks/suite_compiles.py out/compiles [--top 25]

Prints the total compile seconds (outermost compilations only: an inner kernel's time is inside its caller's),
per test process (an xdist worker) and per test file, and the kernels compiled by more than one process (the
same code compiled twice: what a shared cache filled in advance would save), with their seconds.
"""
import argparse
import collections
import json
import pathlib


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args()
    processes = {}
    for path in sorted(pathlib.Path(args.folder).glob("compiles-*.json")):
        processes[path.stem.split("-", 1)[1]] = json.loads(path.read_text())
    total = 0.0
    per_file = collections.Counter()
    per_kernel = collections.defaultdict(dict)  # (kernel, signature) -> {process: seconds}
    for process, rows in processes.items():
        outer = sum(seconds for _, _, seconds, depth, _ in rows if depth == 0)
        total += outer
        print(f"process {process}: {outer:.1f} s compiling (outermost), {len(rows)} compilations")
        for kernel, signature, seconds, depth, test in rows:
            if depth == 0:
                per_file[test.split("::")[0]] += seconds
            per_kernel[(kernel, signature)][process] = per_kernel[(kernel, signature)].get(process, 0.0) + seconds
    print(f"\ntotal: {total:.1f} s compiling (outermost) in {len(processes)} processes\n")
    print("by test file (outermost compilations):")
    for name, seconds in per_file.most_common(args.top):
        print(f"  {seconds:8.1f} s  {name}")
    twice = [(key, seen) for key, seen in per_kernel.items() if len(seen) > 1]
    print(f"\n{len(twice)} kernels (with their signature) compiled by more than one process; the costliest "
          "(inclusive):")
    for (kernel, signature), seen in sorted(twice, key=lambda item: -sum(item[1].values()))[:args.top]:
        print(f"  {sum(seen.values()):8.1f} s in {len(seen)} processes  {kernel}{signature[:60]}")


if __name__ == "__main__":
    main()

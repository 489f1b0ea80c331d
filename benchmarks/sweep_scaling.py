"""Sweeps on dask.distributed: runs per second against workers, and what the cluster costs.

Problem: the paper's section 8 scene (n = 100 branches, h = 1e-3, stepper
``projected``), shortened to ``--stop-time`` seconds, swept over
``--runs`` forcing amplitudes (summaries only).

Measured in one run of this script, on the machine it runs on:

* ``single``: the sum of the runs' times done one by one in this process with
  :func:`summary.summarize` (compiled, warm): the work itself;
* for 1 and 2 workers of a LocalCluster (warm: a first small sweep has loaded
  the kernels in every worker), the wall time of the sweep with the default
  batching and with one run per task; runs per second; the overhead
  fraction ``workers x sweep time / single`` (1 = no overhead; on a machine
  with as many cores as workers, the scheduler, the nanny and this process
  share them with the workers); and the share of the workers' time not
  spent inside a task (dask's task stream): the scheduler's cost;
* ``single`` again at the end: how much the machine itself drifted;
* short runs (T = 0.1 s, 100 steps), where Python per run matters most: one
  task's batch of ``--short-runs`` runs in this process (``runs.run_batch``:
  scene checks, then one compiled call, ``summary.summarize_many``) against
  the same runs one by one (scene check and :func:`summary.summarize` each),
  and the part of the batch spent in its compiled call;
* the time of one full run (T = 500 s) and, from it, what 10^6 runs of the
  paper's scene cost on N machines of C cores at the measured efficiency.

    python benchmarks/sweep_scaling.py [--runs 400] [--stop-time 50] [--short-runs 2000] [--out docs/sweep]
"""
import argparse
import os
import platform
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from common import write_rows  # noqa: E402
from prandtl_fmu import load_scene  # noqa: E402
from prandtl_fmu.scene import read_document, scene_from_document  # noqa: E402
from prandtl_fmu import summary as summary_module  # noqa: E402
from prandtl_fmu.summary import summarize  # noqa: E402
from prandtl_fmu.sweep import sweep  # noqa: E402
from prandtl_fmu.sweep.runs import run_batch  # noqa: E402
from prandtl_fmu.sweep.spec import apply  # noqa: E402

SUMMARY = ["max_abs_x", "final_x", "dissipated", "loop_area"]


def spec(runs, runs_per_task=None):
    tasks = f"\n[tasks]\nruns_per_task = {runs_per_task}\n" if runs_per_task else ""
    return (f'[grid]\n"load.amplitude" = {{ from = 0.05, to = 0.45, count = {runs} }}\n'
            f'[keep]\nsummary = {SUMMARY!r}\n'.replace("'", '"') + tasks)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=400)
    parser.add_argument("--stop-time", type=float, default=50.0)
    parser.add_argument("--short-runs", type=int, default=2000)
    parser.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "docs", "sweep"))
    args = parser.parse_args()
    from distributed import Client, LocalCluster, get_task_stream

    document, source = read_document("paper-section-8")
    document["solver"] = dict(document["solver"], stop_time=args.stop_time)
    folder = tempfile.mkdtemp(prefix="sweep-bench-")

    # the work itself: every run alone, in this process, warm
    summarize(scene_from_document(document, source), quantities=SUMMARY)
    amplitudes = [0.05 + 0.4 * i / (args.runs - 1) for i in range(args.runs)]

    def one_by_one():
        start = time.perf_counter()
        for amplitude in amplitudes:
            summarize(scene_from_document(apply(document, {"load.amplitude": amplitude}), source), quantities=SUMMARY)
        return time.perf_counter() - start

    single = one_by_one()
    rows = [{"configuration": "one by one in-process", "workers": 0, "runs_per_task": "", "seconds": single,
             "runs_per_second": args.runs / single, "overhead_fraction": 1.0, "scheduler_share": ""}]
    print(f"single: {args.runs} runs in {single:.3f} s ({single / args.runs * 1e3:.2f} ms per run)")

    rows += short_runs(document, source, args.short_runs)

    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
            with Client(cluster) as client:
                sweep(document, _write(folder, "warm.toml", spec(2 * workers)), client)  # warm-up: every worker loads the kernels
                for runs_per_task in (None, 1):
                    path = _write(folder, f"sweep-{workers}-{runs_per_task}.toml", spec(args.runs, runs_per_task))
                    with get_task_stream(client) as stream:
                        start = time.perf_counter()
                        frame = sweep(document, path, client)
                        seconds = time.perf_counter() - start
                    computing = sum(part["stop"] - part["start"] for task in stream.data
                                    for part in task["startstops"] if part["action"] == "compute")
                    share = 1 - computing / (workers * seconds)
                    assert len(frame) == args.runs and (frame["error"] == "").all()
                    label = "default batching" if runs_per_task is None else "one run per task"
                    rows.append({"configuration": f"LocalCluster, {label}", "workers": workers,
                                 "runs_per_task": runs_per_task or "default", "seconds": seconds,
                                 "runs_per_second": args.runs / seconds,
                                 "overhead_fraction": workers * seconds / single, "scheduler_share": share})
                    print(f"{workers} worker(s), {label}: {seconds:.3f} s, {args.runs / seconds:.1f} runs/s, "
                          f"overhead fraction {workers * seconds / single:.3f}, time not in a run {share:.1%}")

    again = one_by_one()  # the machine's drift over the measurement
    rows.append({"configuration": "one by one in-process, again", "workers": 0, "runs_per_task": "",
                 "seconds": again, "runs_per_second": args.runs / again, "overhead_fraction": again / single,
                 "scheduler_share": ""})
    full = load_scene("paper-section-8")
    summarize(full, quantities=SUMMARY)
    start = time.perf_counter()
    summarize(full, quantities=SUMMARY)
    one_full = time.perf_counter() - start
    efficiency = min(r["overhead_fraction"] for r in rows if r["workers"] == 2)
    rows.append({"configuration": "one full run (T = 500 s)", "workers": 0, "runs_per_task": "",
                 "seconds": one_full, "runs_per_second": 1 / one_full, "overhead_fraction": "",
                 "scheduler_share": ""})
    write_rows(os.path.join(args.out, "sweep_scaling.csv"), rows)
    lines = ["# 10^6 runs of the paper's scene (T = 500 s), extrapolated from one run of benchmarks/sweep_scaling.py",
             "", f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores. One run: "
             f"{one_full:.3f} s. Overhead fraction measured with 2 workers: {efficiency:.3f}.", "",
             "| machines x cores | hours |", "|---|---|"]
    for machines, cores in ((1, 2), (1, 16), (10, 16), (100, 16)):
        hours = 1e6 * one_full * efficiency / (machines * cores) / 3600
        lines.append(f"| {machines} x {cores} | {hours:.2f} |")
    with open(os.path.join(args.out, "million_runs.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def short_runs(document, source, count):
    """Per-run cost of short runs (T = 0.1 s) in one task: batched against one by one."""
    short = dict(document, solver=dict(document["solver"], stop_time=0.1))
    quantities = ["max_abs_x", "final_x", "dissipated"]
    runs = [(i, {"load.amplitude": 0.05 + 0.4 * i / (count - 1)}) for i in range(count)]
    run_batch(short, source, ["load.amplitude"], runs[:2], quantities, False)  # warm
    compiled = []
    run = summary_module._Batch.run

    def timed(self, outcomes, wanted):  # the time inside the compiled call and the unpacking after it
        start = time.perf_counter()
        run(self, outcomes, wanted)
        compiled.append(time.perf_counter() - start)

    summary_module._Batch.run = timed
    start = time.perf_counter()
    table = run_batch(short, source, ["load.amplitude"], runs, quantities, False)
    batched = time.perf_counter() - start
    summary_module._Batch.run = run
    assert all(error == "" for error in table["error"])
    start = time.perf_counter()
    for _, values in runs:
        summarize(scene_from_document(apply(short, values), source), quantities=quantities)
    alone = time.perf_counter() - start
    print(f"short runs (T = 0.1 s): batched {batched / count * 1e6:.0f} us a run ({len(compiled)} compiled "
          f"call(s): {sum(compiled) / count * 1e6:.0f} us a run), one by one {alone / count * 1e6:.0f} us a run")
    return [{"configuration": f"short runs (T = 0.1 s), one task of {count} runs, in-process", "workers": 0,
             "runs_per_task": count, "seconds": batched, "runs_per_second": count / batched,
             "overhead_fraction": "", "scheduler_share": ""},
            {"configuration": "  of which the compiled call (and unpacking)", "workers": 0,
             "runs_per_task": count, "seconds": sum(compiled), "runs_per_second": count / sum(compiled),
             "overhead_fraction": "", "scheduler_share": ""},
            {"configuration": "short runs one by one (scene check + summarize each)", "workers": 0,
             "runs_per_task": 1, "seconds": alone, "runs_per_second": count / alone,
             "overhead_fraction": "", "scheduler_share": ""}]


def _write(folder, name, text):
    path = os.path.join(folder, name)
    with open(path, "w") as fh:
        fh.write(text)
    return path


if __name__ == "__main__":
    main()

"""Sweeps: many runs of one scene on dask.distributed (parameter studies, Monte Carlo).

    from prandtl_fmu.sweep import sweep
    frame = sweep("paper-section-8", "amplitude.toml", out="amplitude-sweep")   # a LocalCluster on this machine
    frame = sweep(scene, spec, client=Client("tcp://scheduler:8786"))            # an existing cluster

The sweep file (:mod:`.spec`) names scene keys and their values; the runs are
split into tasks of many runs each (:mod:`.runs`: one task is a batch, not a
run, so that the scheduler's cost stays small against the work), the rows go to
a folder of Parquet files as tasks finish (:mod:`.store`), and the result is a
pandas DataFrame with one row per run: its number, its values, the summary
quantities (``summary.SUMMARIES``), optionally its output grid, and the
``error`` and ``warning`` of the run ("" if none). A Monte Carlo sweep ([seeds]: many seeds of the scene's
noise for every grid point) also writes a report, OUT/_report (:mod:`.report`, :mod:`.statistics`): the
mean, standard deviation and histogram of chosen outputs with their confidence intervals, against a law.

Needs the ``sweep`` extra: ``pip install "prandtl_fmu[sweep]"`` (dask[distributed], pandas, pyarrow).
"""
from __future__ import annotations

import dataclasses
import os
import uuid
from typing import Optional, Union

from ..scene import Scene, SceneError, read_document, scene_from_document
from ..summary import default_summaries, summary_problem
from . import report
from .runs import columns, run_batch
from .spec import MAX_RUNS_PER_TASK, SweepError, SweepSpec, apply, load_spec
from .store import Store, read_sweep

__all__ = ["sweep", "load_spec", "read_sweep", "SweepError", "SweepSpec", "plan"]


class Plan:
    """What a sweep will do, checked before any run: the scene document, the spec, the columns, the tasks."""

    def __init__(self, document: dict, source: str, spec: SweepSpec):
        self.document, self.source = document, source
        self.spec = spec = _with_seed_key(spec, document, source)
        run0 = spec.values(0, 1)[0][1]
        try:
            scene = scene_from_document(apply(document, run0), f"{source} with the first run's values")
        except SceneError as exc:
            raise SweepError(str(exc)) from None
        stepper = scene.solver.stepper
        if spec.summary is None:
            self.summary = default_summaries(scene, stepper)
            if spec.statistics is not None:  # what the report asks for by name is kept too
                asked = list(spec.statistics.outputs or ()) + [law.output for law in spec.laws]
                self.summary += [q for q in dict.fromkeys(asked) if q not in self.summary]
            problem = summary_problem(scene, stepper, self.summary)
            if problem:
                raise SweepError(f"{spec.source}: [statistics]: {problem}")
        else:
            problem = summary_problem(scene, stepper, spec.summary)
            if problem:
                raise SweepError(f"{spec.source}: [keep] summary: {problem}")
            self.summary = list(spec.summary)
        if spec.statistics is not None:
            report.require_scipy()
            _check_laws(spec, document)
        self.columns = columns(spec.keys, self.summary, spec.history)
        self.schema = _schema(spec, run0, self.summary)

    def report(self, frame, out) -> str:
        """Write the Monte Carlo report of ``frame`` (this sweep's rows) into ``out``/_report; its report.md."""
        return report.write_report(frame, self.spec, self.document, self.summary, out,
                                   title=f"{self.source} x {self.spec.source}")

    def manifest(self) -> dict:
        import hashlib
        import json

        scene_digest = hashlib.sha256(json.dumps(self.document, sort_keys=True, default=str).encode()).hexdigest()
        return {"scene": self.source, "scene_digest": scene_digest[:16], "sweep": self.spec.source,
                "sweep_digest": self.spec.digest(), "runs": self.spec.runs, "columns": self.columns}

    def tasks(self, runs_per_task: int) -> list:
        """``[(first, stop)]``: consecutive runs, ``runs_per_task`` each (the last may be shorter)."""
        runs = self.spec.runs
        return [(first, min(runs, first + runs_per_task)) for first in range(0, runs, runs_per_task)]


# groups whose laws are checked before any run (each law's parameters come from its group's scene)
LAW_CHECKS = 10000


def _check_laws(spec: SweepSpec, document: dict) -> None:
    """Make each law of the first LAW_CHECKS groups from the group's scene: a bad parameter (c = 0 at one grid
    point) is one line before any run, not an error after them all."""
    if not spec.laws:
        return
    groups = spec.runs // spec.group_size
    for group in range(min(groups, LAW_CHECKS)):
        values, group_document = report.group_documents(spec, document, [group])[group]
        for position, law in enumerate(spec.laws):
            where = report.law_where(spec, position)
            if values:
                where += " (" + ", ".join(f"{key} = {value!r}" for key, value in values.items()) + ")"
            report.law_density(law, group_document, where)


def _with_seed_key(spec: SweepSpec, document: dict, source: str) -> SweepSpec:
    """The spec with its [seeds] key named: the scene's seeded load's seed when the file gives none."""
    if spec.seeds is None or spec.seeds.key is not None:
        return spec
    key = report.seed_key(document)
    if key is None:
        raise SweepError(f"{spec.source}: [seeds] key: {source} has no seeded load ([load] kind = \"random\" or "
                         "\"white_noise\", or noise_intensity on another load): name the key")
    if key in spec.keys:
        raise SweepError(f"{spec.source}: [seeds]: the scene's seed {key} already varies in [grid] or [random]")
    return dataclasses.replace(spec, seeds=dataclasses.replace(spec.seeds, key=key))


def plan(scene, spec) -> Plan:
    """Check a sweep without running it (:class:`Plan`); SweepError names the culprit."""
    if isinstance(scene, Scene):
        raise SweepError("sweep: give the scene as a file name (or its TOML document as a dict), not a Scene "
                         "object: a sweep sets keys of the file")
    if isinstance(scene, dict):
        document, source = scene, "<scene>"
    else:
        try:
            document, source = read_document(scene)
        except SceneError as exc:
            raise SweepError(str(exc)) from None
    return Plan(document, source, load_spec(spec))


def default_runs_per_task(runs: int, workers: int) -> int:
    """About 8 tasks per worker (so that a slow or lost worker delays little), at most MAX_RUNS_PER_TASK runs
    each."""
    return max(1, min(MAX_RUNS_PER_TASK, -(-runs // (8 * max(1, workers)))))


def sweep(scene, spec, client=None, *, out: Optional[Union[str, os.PathLike]] = None, resume: bool = False,
          scheduler: Optional[str] = None, workers: Optional[int] = None, progress: Optional[bool] = None):
    """Run the sweep ``spec`` (a file, a dict or a :class:`SweepSpec`) of ``scene`` (a file or packaged scene
    name, or its TOML document as a dict) and return a pandas DataFrame, one row per run, sorted by run.

    ``client``: a ``dask.distributed.Client`` to run on; else one connected to ``scheduler``
    (``tcp://host:port``); else a ``LocalCluster`` of ``workers`` processes (default: one per core), closed at
    the end. ``out``: a folder that receives the rows as tasks finish (:mod:`.store`); ``resume`` continues a
    sweep there, running only its unfinished tasks. With [seeds], [statistics] or [law] in the sweep file the
    Monte Carlo report (:mod:`.report`) is written into ``out``/_report at the end (a new [law] with
    ``resume`` on a finished sweep redoes only the report). SweepError (one line) for a bad sweep, scene or folder,
    before any run; RuntimeError if a task fails (its message names the runs).
    """
    the_plan = plan(scene, spec)
    _require_dask()
    store = Store(out, the_plan.manifest(), resume) if out is not None else None  # checked before a cluster starts
    owned = []
    try:
        if client is None:
            client = _client(scheduler, workers, owned)
        worker_count = len(client.scheduler_info().get("workers", {})) or 1
        runs_per_task = the_plan.spec.runs_per_task or default_runs_per_task(the_plan.spec.runs, worker_count)
        if store is not None:
            runs_per_task = store.start(runs_per_task)
        tables = _run(client, the_plan, runs_per_task, store, progress)
    finally:
        for thing in reversed(owned):
            thing.close()
    if store is not None:
        frame = read_sweep(store.out)
        if the_plan.spec.statistics is not None:
            the_plan.report(frame, store.out)
        return frame
    import pyarrow as pa

    return pa.concat_tables(tables).to_pandas().sort_values("run", kind="stable").reset_index(drop=True)


def _run(client, the_plan: Plan, runs_per_task: int, store: Optional[Store], progress):
    import pyarrow as pa
    from distributed import as_completed

    from ..stepping import _progress_bar

    done = store.finished() if store is not None else set()
    todo = [(first, stop) for first, stop in the_plan.tasks(runs_per_task) if first not in done]
    spec = the_plan.spec
    tag = uuid.uuid4().hex[:8]
    futures = {}

    def submit(first, stop):
        future = client.submit(run_batch, the_plan.document, the_plan.source, spec.keys, spec.values(first, stop),
                               the_plan.summary, spec.history, key=f"prandtl-sweep-{tag}-{first}", pure=False)
        futures[future] = (first, stop)
        return future

    # Workers on this machine share its numba cache: the first task alone compiles the kernels, once, and the
    # others load them (each worker compiled them at the same time before: the CPU of one compile per worker).
    later = todo[1:] if len(todo) > 1 and _workers_share_this_machine(client) else []
    pending = as_completed([submit(first, stop) for first, stop in todo[:len(todo) - len(later)]])
    bar = _progress_bar(progress, total=sum(stop - first for first, stop in todo), label="sweep runs")
    tables = []
    try:
        for future in pending:
            first, stop = futures[future]
            try:
                rows = future.result()
            except Exception as exc:
                kept = f"; the finished runs are in {store.out} (--resume continues)" if store is not None else ""
                raise RuntimeError(f"sweep: the task of runs {first}..{stop - 1} failed: "
                                   f"{type(exc).__name__}: {exc}{kept}") from exc
            for task in later:  # the first task is done: its kernels are in the cache
                pending.add(submit(*task))
            later = []
            table = pa.Table.from_pydict(rows, schema=the_plan.schema)
            if store is not None:
                store.write(first, stop, table)
            else:
                tables.append(table)
            bar.update(stop - first)
    finally:
        bar.close()
        client.cancel(list(futures))
    return tables


def _workers_share_this_machine(client) -> bool:
    """Whether every worker of ``client`` runs on this machine's loopback address (a LocalCluster: they share this
    machine's numba cache), and there are several."""
    from urllib.parse import urlsplit

    try:
        workers = list(client.scheduler_info().get("workers", {}))
    except Exception:  # a scheduler that does not say: submit as before
        return False
    hosts = {urlsplit(address).hostname for address in workers}
    return len(workers) > 1 and hosts <= {"127.0.0.1", "localhost", "::1"}


def _schema(spec: SweepSpec, run0: dict, summary: list):
    import pyarrow as pa

    fields = [("run", pa.int64())]
    for key in spec.keys:
        value = run0[key]
        kind = pa.string() if isinstance(value, str) else pa.int64() if isinstance(value, int) else pa.float64()
        fields.append((key, kind))
    fields += [(q, pa.float64()) for q in summary]
    if spec.history:
        fields += [(name, pa.list_(pa.float64())) for name in ("time", "x", "v", "reaction")]
    fields += [("error", pa.string()), ("warning", pa.string())]
    return pa.schema(fields)


def _require_dask():
    try:
        import distributed  # noqa: F401
        import pandas  # noqa: F401
        import pyarrow  # noqa: F401
    except ImportError as exc:
        raise SweepError(f"sweeps need the sweep extra ({exc.name} is missing): pip install "
                         "\"prandtl_fmu[sweep]\"") from None


def _client(scheduler, workers, owned):
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise SweepError(f"--scheduler {scheduler}: cannot connect: {exc}") from None
        owned.append(client)
        return client
    # dashboard on a free port (its address is in client.dashboard_link): never a clash with another cluster
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    owned.append(cluster)
    client = Client(cluster)
    owned.append(client)
    return client

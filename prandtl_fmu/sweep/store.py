"""A sweep's results on disk: a folder of Parquet files, one per finished task, written as tasks finish.

    OUT/_sweep.json                         what the sweep is (scene and sweep digests, runs, task size, columns)
    OUT/runs-000000000-000001999.parquet    the rows of runs 0 .. 1999, one row per run

A part file appears whole or not at all (written to a temporary name, then
renamed), so an interrupted sweep keeps every task it finished, and
``--resume`` runs only the tasks whose file is missing. ``pandas.read_parquet(OUT)``
or :func:`read_sweep` reads them all.
"""
from __future__ import annotations

import json
import os
import re

from .spec import SweepError

MANIFEST = "_sweep.json"  # a leading _ : pyarrow and pandas.read_parquet(OUT) skip it
_PART = re.compile(r"^runs-([0-9]{9})-([0-9]{9})\.parquet$")


def part_name(first: int, stop: int) -> str:
    return f"runs-{first:09d}-{stop - 1:09d}.parquet"


class Store:
    """The folder ``out`` of one sweep (see the module docstring)."""

    def __init__(self, out, manifest: dict, resume: bool):
        """Check the folder (refuse one that holds another sweep, or this one without ``resume``)."""
        self.out = os.fspath(out)
        self.path = os.path.join(self.out, MANIFEST)
        self.manifest = manifest
        self.previous = None
        if os.path.exists(self.path):
            if not resume:
                raise SweepError(f"{self.out}: holds a sweep already: --resume finishes it, or choose another --out")
            try:
                with open(self.path) as fh:
                    self.previous = json.load(fh)
                int(self.previous["runs_per_task"])
            except (OSError, ValueError, KeyError, TypeError) as exc:
                raise SweepError(f"{self.path}: unreadable ({exc}); choose another --out") from None
            for key in ("scene_digest", "sweep_digest", "runs", "columns"):
                if self.previous.get(key) != manifest.get(key):
                    raise SweepError(f"{self.out}: holds another sweep ({key} differs): --resume continues only the "
                                     "same scene and sweep file; choose another --out")
        elif os.path.isdir(self.out) and any(_PART.match(name) for name in os.listdir(self.out)):
            raise SweepError(f"{self.out}: holds sweep results without {MANIFEST}; choose another --out")
        elif os.path.exists(self.out) and not os.path.isdir(self.out):
            raise SweepError(f"{self.out}: not a folder")

    def start(self, runs_per_task: int) -> int:
        """Write the manifest of a new sweep; the task size to use (a resumed sweep keeps its own)."""
        if self.previous is not None:
            self.manifest = dict(self.previous)
            return int(self.previous["runs_per_task"])
        self.manifest = dict(self.manifest, runs_per_task=runs_per_task)
        try:
            os.makedirs(self.out, exist_ok=True)
            _write_atomic(self.path, json.dumps(self.manifest, indent=2).encode())
        except OSError as exc:
            raise SweepError(f"{self.out}: cannot write there: {exc.strerror}") from None
        return runs_per_task

    def finished(self) -> set:
        """First runs of the tasks whose part file exists."""
        return {int(m.group(1)) for m in map(_PART.match, os.listdir(self.out)) if m}

    def write(self, first: int, stop: int, table) -> None:
        """Write the rows (a pyarrow Table) of runs first .. stop - 1."""
        import pyarrow.parquet as pq

        path = os.path.join(self.out, part_name(first, stop))
        temporary = os.path.join(self.out, f".{os.path.basename(path)}.{os.getpid()}.tmp")
        pq.write_table(table, temporary)
        os.replace(temporary, path)


def _write_atomic(path, data: bytes) -> None:
    temporary = f"{path}.{os.getpid()}.tmp"
    with open(temporary, "wb") as fh:
        fh.write(data)
    os.replace(temporary, path)


def read_sweep(out):
    """Every finished row of the sweep in folder ``out`` as a pandas DataFrame, sorted by run."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = os.fspath(out)
    names = sorted(name for name in os.listdir(out) if _PART.match(name))
    if not names:
        raise SweepError(f"{out}: no finished runs")
    table = pa.concat_tables([pq.read_table(os.path.join(out, name)) for name in names])
    return table.to_pandas().sort_values("run", kind="stable").reset_index(drop=True)

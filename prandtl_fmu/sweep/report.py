"""The report of a Monte Carlo sweep: per group of runs (:meth:`spec.SweepSpec.group`) and chosen output, the
mean, the standard deviation and a histogram with their confidence intervals (:mod:`.statistics`), and the
histogram against a law with Pearson's chi-square test.

    OUT/_report/report.md          the tables, the tests, the figures
    OUT/_report/statistics.csv     one row per group and output (STATISTICS_COLUMNS, after the group's keys)
    OUT/_report/histograms.csv     one row per group, output and bin (HISTOGRAM_COLUMNS)
    OUT/_report/law-<output>-<group>.png   the histogram with its Wilson bars and the law's density

The folder's name starts with "_": ``pandas.read_parquet(OUT)`` skips it. A run counts in its group's
statistics when it has no error and a finite value; ``failed`` counts the others.
"""
from __future__ import annotations

import math
import os
import re

import numpy as np

from .spec import LawSpec, SweepError, SweepSpec, apply
from .statistics import LAWS, NOISE, chi_square_test, histogram, mean_interval, std_interval

REPORT_FOLDER = "_report"
STATISTICS_COLUMNS = ["output", "runs", "n", "failed", "mean", "mean_low", "mean_high", "std", "std_low",
                      "std_high", "min", "max", "confidence", "law", "chi2", "dof", "p_value"]
HISTOGRAM_COLUMNS = ["group", "output", "bin", "low", "high", "count", "fraction", "fraction_low", "fraction_high",
                     "density", "density_low", "density_high", "law_fraction", "law_count"]
MAX_FIGURES = 12  # per law: the first groups only (a grid of 1000 points would make 1000 figures)
_SCENE_KEY = re.compile(r"^([a-z_]+)\.([A-Za-z_][A-Za-z_0-9]*(?:\.[A-Za-z_][A-Za-z_0-9]*)*)(?:\[([0-9]+)\])?$")


def require_scipy() -> None:
    try:
        import scipy  # noqa: F401
    except ImportError:
        raise SweepError("the Monte Carlo report ([seeds], [statistics], [law]) needs scipy: pip install scipy") \
            from None


def noise_key(document: dict) -> str:
    """The scene key of the noise intensity sigma: ``load.intensity`` of a white-noise load, else
    ``load.noise_intensity`` (white noise added to another load)."""
    load = document.get("load", {})
    return "load.intensity" if isinstance(load, dict) and load.get("kind") == "white_noise" else "load.noise_intensity"


def seed_key(document: dict):
    """The scene's seeded load's seed key (``load.seed`` of kind "random" or "white_noise", ``load.noise_seed``
    of a load with added noise), or None."""
    load = document.get("load", {})
    if not isinstance(load, dict):
        return None
    if load.get("kind") in ("random", "white_noise"):
        return "load.seed"
    if "noise_intensity" in load or "noise_seed" in load:
        return "load.noise_seed"
    return None


def read_key(document: dict, key: str):
    """The value of ``key`` (table.key, table.key.key, table.key[i]) in a scene document, or None if absent."""
    table, path, index = _SCENE_KEY.match(key).groups()
    target = document.get(table)
    for part in path.split("."):
        if not isinstance(target, dict) or part not in target:
            return None
        target = target[part]
    if index is not None:
        if not isinstance(target, list) or int(index) > len(target):
            return None
        target = target[int(index) - 1]
    return target


def law_density(law: LawSpec, document: dict, where: str):
    """The :class:`statistics.Density` of ``law`` with its parameters from [law] or the scene ``document``
    (one group's); SweepError names the missing or bad parameter."""
    kind = LAWS[law.density]
    values = {}
    for name, default in kind.parameters.items():
        source = law.parameters.get(name, default)
        if source is None:
            raise SweepError(f"{where}: {law.density} needs {name} (a number or a scene key)")
        if isinstance(source, str):
            key = noise_key(document) if source == NOISE else source
            value = read_key(document, key)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise SweepError(f"{where}: {name} is the scene's {key}, which it does not have: give {name} = ... "
                                 "in the law")
            source = float(value)
        values[name] = source
    try:
        return kind.make(**values)
    except ValueError as exc:
        raise SweepError(f"{where}: {exc}") from None


def law_where(spec: SweepSpec, position: int) -> str:
    return f"{spec.source}: [law]" if len(spec.laws) == 1 else f"{spec.source}: [[law]] {position + 1}"


def outputs(spec: SweepSpec, summary: list) -> list:
    """The outputs the report covers: [statistics] outputs, else every kept summary quantity."""
    chosen = spec.statistics.outputs if spec.statistics and spec.statistics.outputs else summary
    return [q for q in chosen if q in summary]


def group_documents(spec: SweepSpec, document: dict, groups) -> dict:
    """group -> (its values of the group keys, its scene document)."""
    keys = spec.group_keys
    found = {}
    for group in groups:
        run = int(group) * spec.group_size
        values = {key: value for key, value in spec.values(run, run + 1)[0][1].items() if key in keys}
        found[int(group)] = (values, apply(document, values))
    return found


def tables(frame, spec: SweepSpec, document: dict, summary: list):
    """``(statistics, histograms, figures)``: the two DataFrames of the report, and per law the data of its
    figures ``[(law, group, values, histogram, density, fit)]``."""
    import pandas as pd

    statistics = spec.statistics
    confidence = statistics.confidence
    chosen = outputs(spec, summary)
    laws = {law.output: (position, law) for position, law in enumerate(spec.laws)}
    frame = frame.assign(_group=frame["run"] // spec.group_size)
    groups = group_documents(spec, document, sorted(frame["_group"].unique()))
    rows, bins_rows, figures = [], [], []
    for group, runs in frame.groupby("_group", sort=True):
        group = int(group)
        values, group_document = groups[group]
        ok = runs["error"] == ""
        for output in chosen:
            column = runs[output].to_numpy(dtype=float)
            sample = column[ok.to_numpy() & np.isfinite(column)]
            n = sample.size
            row = {"group": group, **values, "output": output, "runs": len(runs), "n": n, "failed": len(runs) - n,
                   "confidence": confidence, "law": "", "chi2": math.nan, "dof": math.nan, "p_value": math.nan}
            row["mean"], row["mean_low"], row["mean_high"] = mean_interval(sample, confidence) if n else (math.nan,) * 3
            row["std"], row["std_low"], row["std_high"] = std_interval(sample, confidence)
            row["min"], row["max"] = (float(sample.min()), float(sample.max())) if n else (math.nan, math.nan)
            rows.append(row)
            if not n:
                continue
            hist = histogram(sample, statistics.bins, confidence)
            law_fraction = np.full(hist.counts.size, math.nan)
            if output in laws:
                position, law = laws[output]
                density = law_density(law, group_document, law_where(spec, position))
                fit = chi_square_test(sample, hist.edges, density)
                law_fraction = fit.expected
                row.update(law=f"{law.density}: {density.label}", chi2=fit.chi2, dof=fit.dof, p_value=fit.p_value)
                figures.append((law, group, values, hist, density, fit))
            for j in range(hist.counts.size):
                bins_rows.append({
                    "group": group, "output": output, "bin": j, "low": hist.edges[j], "high": hist.edges[j + 1],
                    "count": int(hist.counts[j]), "fraction": hist.fraction[j], "fraction_low": hist.fraction_low[j],
                    "fraction_high": hist.fraction_high[j], "density": hist.density[j],
                    "density_low": hist.density_low[j], "density_high": hist.density_high[j],
                    "law_fraction": law_fraction[j], "law_count": law_fraction[j] * n})
    columns = ["group", *spec.group_keys, *STATISTICS_COLUMNS]
    return (pd.DataFrame(rows, columns=columns), pd.DataFrame(bins_rows, columns=HISTOGRAM_COLUMNS), figures)


def write_report(frame, spec: SweepSpec, document: dict, summary: list, out, title: str = "") -> str:
    """Write the report of the sweep ``frame`` into ``out``/_report (see the module docstring); its report.md."""
    statistics, histograms, figures = tables(frame, spec, document, summary)
    folder = os.path.join(os.fspath(out), REPORT_FOLDER)
    try:
        os.makedirs(folder, exist_ok=True)
        for name in os.listdir(folder):  # a report written again (a new [law]) keeps no figure of the old one
            if name.startswith("law-") and name.endswith(".png"):
                os.remove(os.path.join(folder, name))
        statistics.to_csv(os.path.join(folder, "statistics.csv"), index=False)
        histograms.to_csv(os.path.join(folder, "histograms.csv"), index=False)
        images, note = _figures(figures, folder)
        path = os.path.join(folder, "report.md")
        with open(path, "w") as fh:
            fh.write(markdown(statistics, spec, title, images, note))
    except OSError as exc:
        raise SweepError(f"{folder}: cannot write the report: {exc.strerror}") from None
    return path


def markdown(statistics, spec: SweepSpec, title: str, images: list, note: str) -> str:
    confidence = spec.statistics.confidence
    lines = [f"# Monte Carlo: {title or spec.source}", ""]
    what = f"{spec.seeds.count} seeds ({spec.seeds.key} = {spec.seeds.first} .. " \
           f"{spec.seeds.first + spec.seeds.count - 1})" if spec.seeds else f"{spec.samples} random samples"
    lines += [f"{spec.runs} runs: {what} per group, {spec.runs // spec.group_size} group(s). Intervals at "
              f"{100 * confidence:g} %: the mean's Student t, the standard deviation's chi-square (exact for "
              "normal values), each bin's Wilson score interval. The chi-square test merges adjacent cells (the "
              "bins and the two tails) until each expects >= 5 runs; dof = cells - 1 (nothing fitted). Files: "
              "statistics.csv, histograms.csv.", ""]
    keys = spec.group_keys
    header = ["group", *keys, "output", "n", "failed", "mean", f"mean {100 * confidence:g} % CI", "std",
              f"std {100 * confidence:g} % CI", "law", "chi2 / dof", "p-value"]
    lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in statistics.to_dict("records"):
        fit = f"{row['chi2']:.4g} / {row['dof']:.0f}" if row["law"] else ""
        p = f"{row['p_value']:.3g}" if row["law"] else ""
        cells = [str(row["group"]), *(_text(row[key]) for key in keys), row["output"], str(row["n"]),
                 str(row["failed"]), _text(row["mean"]), f"[{_text(row['mean_low'])}, {_text(row['mean_high'])}]",
                 _text(row["std"]), f"[{_text(row['std_low'])}, {_text(row['std_high'])}]", row["law"], fit, p]
        lines.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
    lines.append("")
    for name in images:
        lines += [f"![{name}]({name})", ""]
    if note:
        lines += [note, ""]
    return "\n".join(lines)


def _text(value) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _figures(figures, folder) -> tuple:
    """The PNGs of the laws (at most MAX_FIGURES groups per law); (their names, a note on what is left out)."""
    if not figures:
        return [], ""
    try:
        import matplotlib
    except ImportError:
        return [], "No figures: matplotlib is missing (pip install 'prandtl_fmu[plot]')."
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names, left = [], 0
    per_law = {}
    for law, group, values, hist, density, fit in figures:
        per_law[law.output] = per_law.get(law.output, 0) + 1
        if per_law[law.output] > MAX_FIGURES:
            left += 1
            continue
        name = f"law-{law.output}-{group}.png"
        figure = plot_histogram(hist, density, fit, law.output, values)
        figure.savefig(os.path.join(folder, name), dpi=110)
        plt.close(figure)
        names.append(name)
    note = f"{left} figure(s) not drawn (at most {MAX_FIGURES} groups per law); histograms.csv has them all." \
        if left else ""
    return names, note


def plot_histogram(hist, density, fit, output: str, values: dict):
    """A figure: the histogram's densities with their Wilson bars, and the law's density."""
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(6.4, 4.2))
    centres = 0.5 * (hist.edges[1:] + hist.edges[:-1])
    axes.bar(centres, hist.density, width=hist.widths, color="#c6dbef", edgecolor="#4a6f8a", linewidth=0.6,
             label=f"{hist.n} runs")
    axes.errorbar(centres, hist.density, yerr=[hist.density - hist.density_low, hist.density_high - hist.density],
                  fmt="none", ecolor="#08306b", elinewidth=1.0, capsize=2,
                  label=f"Wilson {100 * hist.confidence:g} % interval")
    pad = 0.15 * (hist.edges[-1] - hist.edges[0])
    grid = np.linspace(hist.edges[0] - pad, hist.edges[-1] + pad, 600)
    axes.plot(grid, density.pdf(grid), color="#cb181d", linewidth=1.6, label=density.label)
    axes.set_xlabel(output)
    axes.set_ylabel("probability density")
    where = ", ".join(f"{key} = {value:.4g}" if isinstance(value, float) else f"{key} = {value}"
                      for key, value in values.items())
    axes.set_title(f"{output}{': ' + where if where else ''}\nchi2 = {fit.chi2:.3g}, dof = {fit.dof}, "
                   f"p = {fit.p_value:.3g}", fontsize=10)
    axes.set_ylim(0, 1.3 * max(float(hist.density_high.max()), float(density.pdf(grid).max())))  # room for the legend
    axes.legend(fontsize=8, loc="upper left")
    figure.tight_layout()
    return figure

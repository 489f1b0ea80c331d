"""Figures: the hysteresis loop (reaction against x) and x(t); how every figure of the tools is saved."""
from __future__ import annotations

import io
import os


def plot_result(result, path: str, note: str = "") -> None:
    """Write a PNG with the loop reaction(x) and the displacement x(t) of a :class:`Result`; ``note`` is
    added to the title (e.g. that the rows were thinned)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (loop, history) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    loop.plot(result.x, result.reaction, lw=0.8)
    loop.set_xlabel("x (m)")
    loop.set_ylabel("reaction (N)")
    loop.set_title("hysteresis loop")
    loop.grid(alpha=0.3)
    history.plot(result.time, result.x, lw=0.8)
    history.set_xlabel("t (s)")
    history.set_ylabel("x (m)")
    history.set_title("displacement")
    history.grid(alpha=0.3)
    title = f"{result.scene.name}: stepper {result.stepper}, h = {result.scene.solver.step:g} s"
    fig.suptitle(f"{title} ({note})" if note else title)
    save_figure(fig, path)


# a network's x(t): at most NODES_DRAWN nodes, evenly picked; up to LEGEND_NODES (the colours of matplotlib's
# default cycle) named in a legend, beyond that coloured by a colour map with its colour bar (no colour twice)
NODES_DRAWN = 40
LEGEND_NODES = 10


def plot_network(result, path: str) -> None:
    """Write a figure of a network run: the loop F against the load node's displacement, and the nodes' x(t)
    (:data:`NODES_DRAWN` at most, evenly picked, for a long chain)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    network = result.scene.network
    load = network.nodes[network.load_node]
    fig, (loop, history) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    loop.plot(result.column(f"x_{load}"), result.F, lw=0.8)
    loop.set_xlabel(f"x_{load} (m)")
    loop.set_ylabel("F (N)")
    loop.set_title(f"load against the displacement of {load}")
    loop.grid(alpha=0.3)
    picked = np.unique(np.linspace(0, network.n - 1, min(network.n, NODES_DRAWN)).round().astype(int))
    if len(picked) <= LEGEND_NODES:  # few curves: each its colour of the default cycle, named in a legend
        for j in picked:
            history.plot(result.time, result.x[:, j], lw=0.8, label=network.nodes[j])
        history.legend(fontsize=7, ncol=2)
    else:  # more nodes than the cycle has colours: a colour map by the node's place, and its colour bar
        colours = plt.get_cmap("viridis")
        scale = matplotlib.colors.Normalize(0, network.n - 1)
        for j in picked:
            history.plot(result.time, result.x[:, j], lw=0.8, color=colours(scale(j)))
        bar = fig.colorbar(matplotlib.cm.ScalarMappable(norm=scale, cmap=colours), ax=history, pad=0.01)
        ticks = np.unique(np.linspace(0, network.n - 1, min(network.n, 6)).round().astype(int))
        bar.set_ticks(ticks, labels=[network.nodes[j] for j in ticks])
        bar.set_label(f"node ({len(picked)} of {network.n} drawn)" if len(picked) < network.n else "node")
    history.set_xlabel("t (s)")
    history.set_ylabel("x (m)")
    history.set_title("displacements")
    history.grid(alpha=0.3)
    fig.suptitle(f"{result.scene.name}: network of {network.n} nodes, stepper {result.stepper}, "
                 f"h = {result.scene.solver.step:g} s")
    save_figure(fig, path)


def image_format(path: str) -> str:
    """The image format named by ``path``'s extension (png, pdf, svg, ...; PNG for a device or a pipe);
    ValueError naming the formats matplotlib writes when it names none of them. Checked before any work."""
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    extension = os.path.splitext(path)[1].lstrip(".").lower()
    if not extension and os.path.exists(path) and not os.path.isfile(path):
        return "png"  # a device or a pipe (/dev/stdout): PNG
    if extension not in formats:
        raise ValueError(f"{path}: unknown image format {extension or '(no extension)'!r}: name the file "
                         f"with one of {', '.join('.' + name for name in sorted(formats))}")
    return extension


def save_figure(fig, path: str, dpi: int = 120) -> None:
    """Render ``fig`` in memory, then write it whole (:func:`outputs.write_output`: atomically, with the usual
    mode; a device's write error raised) and close it."""
    import matplotlib.pyplot as plt

    from .outputs import write_output

    buffer = io.BytesIO()
    try:
        fig.savefig(buffer, format=image_format(path), dpi=dpi)
    finally:
        plt.close(fig)
    write_output(path, buffer.getvalue())

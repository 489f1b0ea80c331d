"""Figures: the hysteresis loop (reaction against x) and x(t)."""
from __future__ import annotations


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
    fig.savefig(path, dpi=120)
    plt.close(fig)

"""The figures: a network's displacements stay readable however many nodes it has."""
import pytest

pytest.importorskip("matplotlib")

from prandtl_fmu import load_scene, plots  # noqa: E402
from prandtl_fmu.network import simulate as simulate_network  # noqa: E402


def _figure_of(scene_name, monkeypatch, stop_time):
    kept = []
    monkeypatch.setattr(plots, "save_figure", lambda fig, path, dpi=120: kept.append(fig))
    scene = load_scene(scene_name).with_solver(stop_time=stop_time)
    plots.plot_network(simulate_network(scene), "unused.png")
    (figure,) = kept
    history = [ax for ax in figure.axes if ax.get_title() == "displacements"][0]
    return figure, history


def test_a_chain_of_many_nodes_is_coloured_by_a_colour_map_with_its_colour_bar(monkeypatch):
    """20 nodes (more than the 10 colours of the default cycle): no legend, no colour twice, a colour bar whose
    ticks name nodes (issue 44.9: the legend gave n1 and n18 the same colour)."""
    figure, history = _figure_of("networks/chain-dynamic", monkeypatch, 0.05)
    colours = [tuple(line.get_color()) for line in history.get_lines()]
    assert len(colours) == 20 and len(set(colours)) == 20
    assert history.get_legend() is None
    bars = [ax for ax in figure.axes if ax is not history and ax.get_ylabel().startswith("node")]
    assert len(bars) == 1
    assert [label.get_text() for label in bars[0].get_yticklabels()][0] == "n1"


def test_a_network_of_few_nodes_keeps_its_legend(monkeypatch):
    figure, history = _figure_of("networks/two-masses-slider", monkeypatch, 0.05)
    assert [text.get_text() for text in history.get_legend().get_texts()] == ["a", "b"]
    assert len(figure.axes) == 2  # no colour bar

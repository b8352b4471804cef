"""The diagnosis figures (``residual_bode``) are laid out with fixed margins instead of a
``tight_layout`` pass (issue 27 item 6: that pass is a second full draw of each figure).  Nothing
may be cut off for it: every tick label, axis label, title and legend entry of the written figure
lies inside the canvas, measured on the drawn figure (the renderer's own text extents, not the
margins the code chose), for responses whose tick labels are as wide as a Bode plot gives (four
decades of magnitude in dB, phase down to −700°, residuals to ±300) and a long title."""

from __future__ import annotations

import numpy as np
import pytest

from physmodel.data.sweep import FrequencySweep
from scenarios import plots
from scenarios.plots import canvas


def _sweep(decades: float, phase_turns: float, resid: float, sigma_db: float = 0.1):
    f = np.tile(np.logspace(-2, 3, 31), 3)
    t = np.repeat([5.0, 35.0, 65.0], 31)
    x = np.log10(f) + 2                                        # 0 … 5
    G = 10 ** (-decades * x / 5) * np.exp(-2j * np.pi * phase_turns * x / 5)
    sd = np.full(f.size, sigma_db)
    data = FrequencySweep(t, f, G, sd, np.full(f.size, 10 * sigma_db), "voltage", "V", "tip_displacement", "mm")
    model = G * np.exp(resid * sigma_db * np.log(10) / 20 * np.sin(x))      # residuals up to ±resid
    return data, model


@pytest.mark.parametrize("decades,turns,resid", [(1.0, 0.3, 1.0), (4.0, 2.0, 300.0)])
def test_every_label_of_the_diagnosis_figure_is_inside_the_canvas(tmp_path, monkeypatch, decades, turns, resid):
    drawn = []
    real = canvas.save_figure

    def keep(fig, path, dpi=120):
        drawn.append(fig)
        return real(fig, path, dpi)

    monkeypatch.setattr(plots.residuals, "save_figure", keep)
    data, model = _sweep(decades, turns, resid)
    title = "after: + viscous_fluid, distributed_cpe"          # the two-effect title of seed 41005
    path = plots.residual_bode(tmp_path / "bode_after.png", data, model, title)
    assert path.stat().st_size > 0 and len(drawn) == 1
    fig = drawn[0]
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    W, H = fig.bbox.width, fig.bbox.height
    # what each panel draws — its tick labels within the view, axis labels, title, legend — as the
    # renderer measures it (Axes.get_tightbbox: drawn artists only)
    assert fig.axes[0].get_legend() is not None and fig.axes[0].get_title()
    for ax in fig.axes:
        bb = ax.get_tightbbox(r)
        assert bb.x0 >= -0.5 and bb.y0 >= -0.5 and bb.x1 <= W + 0.5 and bb.y1 <= H + 0.5, \
            f"{ax.get_ylabel()!r} panel draws at {bb.bounds}, outside the {W:.0f}×{H:.0f} canvas"
    # the panels stay apart
    boxes = [ax.get_window_extent(r) for ax in fig.axes]
    for upper, lower in zip(boxes, boxes[1:]):
        assert lower.y1 < upper.y0


def test_the_before_after_pair_on_one_canvas_draws_the_same_images_as_two_figures(tmp_path):
    """residual_bode_pair draws the second figure by resetting the model's lines of the first:
    both images are pixel for pixel those of two separate residual_bode calls (limits from the
    second model's lines and residuals, the data's bands included), for models whose curves and
    residuals reach past the first one's limits and stay inside them."""
    from matplotlib.image import imread

    data, G = _sweep(1.0, 0.3, 1.0, sigma_db=3.0)           # bands well beyond the curves
    rng = np.random.default_rng(2)
    for G2 in (G * np.exp(2.0 * rng.normal(size=G.size) + 0.8j * rng.normal(size=G.size)),   # wider
               data.response * (1 + 0.001j)):                                                # narrower
        pair = plots.residual_bode_pair((tmp_path / "a.png", tmp_path / "b.png"), data, (G, G2),
                                        ("baseline (before)", "after: + second_mode"))
        one = plots.residual_bode(tmp_path / "a1.png", data, G, "baseline (before)")
        two = plots.residual_bode(tmp_path / "b1.png", data, G2, "after: + second_mode")
        np.testing.assert_array_equal(imread(pair[0]), imread(one))
        np.testing.assert_array_equal(imread(pair[1]), imread(two))
    with pytest.raises(ValueError, match="lines"):
        plots.residual_bode_pair((tmp_path / "a.png", tmp_path / "b.png"), data, (G, G[:-1]), ("x", "y"))

"""Long runs stay readable: ``currents.png`` draws the envelope of the phase currents and a
zoom window on the last periods (three lines over hundreds of periods are a solid block),
with the legends beside the panels; every panel of the run's figures has its time axis."""

from __future__ import annotations

import pytest

import imdrive as im
from imdrive.run.plots import LONG_RUN_PERIODS, currents_figure, electrical_periods


@pytest.fixture(scope="module")
def long_run():
    return im.simulate(im.Scenario.read("sensorless").with_overrides({"simulation.t_end_s": 6.0}))


def test_long_run_currents_have_an_envelope_and_a_zoom(long_run):
    assert electrical_periods(long_run) > LONG_RUN_PERIODS
    fig = currents_figure(long_run)
    env, zoom, dq = fig.axes[:3]
    assert env.collections, "no envelope"
    t_end = float(long_run.time_s[-1])
    lo, hi = zoom.get_xlim()
    assert hi == pytest.approx(t_end) and 0.0 < hi - lo < 0.1 * t_end  # a window at the end
    assert dq.get_xlim() == env.get_xlim()  # the whole-run panels share their time axis
    fig.canvas.draw()
    for ax in (env, zoom, dq):  # legends beside the data, every panel with time tick labels
        assert ax.get_legend().get_window_extent().x0 >= ax.get_window_extent().x1
        assert any(lab.get_text() for lab in ax.get_xticklabels())


def test_short_run_currents_stay_three_lines():
    res = im.simulate(im.Scenario.read("sensorless").with_overrides({"simulation.t_end_s": 0.6}))
    fig = currents_figure(res)
    assert len(fig.axes) == 2 and len(fig.axes[0].lines) == 3


def test_every_panel_of_res_plot_has_time_tick_labels(long_run):
    fig = long_run.plot()
    fig.canvas.draw()
    for ax in fig.axes:
        assert any(lab.get_text() for lab in ax.get_xticklabels()), ax.get_ylabel()

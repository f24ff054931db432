"""A matrix row's costs are timed warm: after an untimed run of the same configuration,
and the captions say so (no stalled timing is dropped)."""

from frictex.app.measure import report_markdown as rmd
from frictex.app.measure import report_matrix as rm

from test_report_tables import SETTINGS


def test_each_case_is_timed_after_an_untimed_run_of_its_configuration(monkeypatch):
    calls = []

    def recording(pipeline, trace, blocks_per_call, duration_s):
        calls.append((pipeline, duration_s))
        return run_blocks(pipeline, trace, blocks_per_call, duration_s)

    run_blocks = rm.run_blocks
    monkeypatch.setattr(rm, "run_blocks", recording)
    rm.Runner(live_s=0.005, plate=False).run(rm.Case("grating-5mm", "fast", 50.0, "sht",
                                                     10_000.0))
    (warm, warm_s), (timed, timed_s) = calls
    assert warm_s == rm.WARM_UP_S < timed_s
    assert warm is not timed  # the timed pipeline starts from t = 0 like any other
    assert timed.timer.seconds["tracking"] > 0 and warm.timer.seconds["tracking"] > 0


def test_cost_captions_say_how_timings_are_taken_and_drop_none():
    caption = rmd.plot_captions(SETTINGS)["error_vs_cost.png"][1]
    assert f"untimed {rm.WARM_UP_S:g} s run of the same configuration" in caption
    assert "counts in no median" not in caption
    assert "no timing is dropped" in caption


def test_a_missed_throughput_target_says_its_timings_were_warm():
    from dataclasses import replace

    from frictex.app.measure.report_doc import headline
    from test_report_tables import row
    slow = replace(row(scene="composed-fine-grating-in-disc"), throughput=replace(
        row().throughput, replay_x_realtime=10.0))
    verdicts = rmd._throughput_verdicts(headline([slow]), SETTINGS)
    assert (f"1 of 1 rows miss it, one timing each after an untimed {rm.WARM_UP_S:g} s run "
            "of the same configuration") in verdicts


def test_a_process_keeps_one_runner_per_motions_contents_not_their_names(monkeypatch):
    """Motions of one name but other contents (an API user's, or a long-lived worker's
    second call) got the first call's runner, and its rows."""
    made = []

    class Recording:
        def __init__(self, live_s, motions, plate):
            made.append(motions)
            self.motions = motions

        def run(self, case):
            return self.motions

    monkeypatch.setattr(rm, "Runner", Recording)
    monkeypatch.setattr(rm, "_RUNNERS", {})
    case = rm.Case("grating-5mm", "m", 50.0, "sht", 10_000.0)
    slow, fast = {"m": rm.MOTIONS["slow"]}, {"m": rm.MOTIONS["fast"]}
    assert rm.run_case(case, motions=slow) == slow
    assert rm.run_case(case, motions=fast) == fast
    assert rm.run_case(case, motions=dict(slow)) == slow and made == [slow, fast]

"""The summary's warnings say a count of 1 in the singular ('1 finger jump was treated
as lift and touch', where it said '1 finger jumps were ...') and other counts in the
plural."""

from types import SimpleNamespace

from frictex.app.engine.summary import Totals, _within_a_block, counted, warnings_of


def warnings_for(jumps=0, out_of_order=0, nonfinite=0, off_structure=0):
    totals = Totals()
    totals.clamps.nonfinite_target = nonfinite
    totals.off_structure = off_structure
    return warnings_of(SimpleNamespace(forces=None),
                       SimpleNamespace(jumps=jumps, out_of_order=out_of_order), totals)


def test_one_of_each_is_said_in_the_singular():
    assert warnings_for(jumps=1, out_of_order=1, nonfinite=1, off_structure=1) == [
        "1 target sample was not finite (NaN or inf) and was commanded 0 um",
        "1 finger jump was treated as lift and touch",
        "1 out-of-order touch sample was dropped",
        "1 finger sample was off the vibrating structure and was held at its edge"]


def test_more_than_one_is_said_in_the_plural():
    assert warnings_for(jumps=3, out_of_order=2) == [
        "3 finger jumps were treated as lift and touch",
        "2 out-of-order touch samples were dropped"]


def test_a_touch_within_a_block():
    one, = _within_a_block({"touches_within_a_block": 1})
    assert one.startswith("1 touch began and lifted within one output block, so no output "
                          "sample is in contact for it (none of its rows")
    two, = _within_a_block({"touches_within_a_block": 2})
    assert two.startswith("2 touches began and lifted") and "for them (none of their" in two


def test_counted():
    assert [counted(n, "touch", "touches") for n in (0, 1, 2)] == [
        "0 touches", "1 touch", "2 touches"]


def test_the_demos_closing_lines_say_one_in_the_singular(capsys):
    from frictex.app.commands.demo import _Ended, _print_lines
    summary = {"cpu_steal_pct": None, "blocks": 1, "output_s": 0.0, "deadline_misses": 1,
               "worst_lateness_ms": 0.5, "clamps_total": 1, "frames": 1, "frame_ms_mean": 1.0, "input_counts": {},
               "control": None, "ended_by": "window", "dropped_record_blocks": 0}
    link = {"state": "closed", "skipped_blocks": 1, "underruns": 1, "unplayed_samples": 0,
            "commanded_samples": 5, "unplayed_by_cause": {}}
    _print_lines(None, summary, _Ended(summary, link, None, None), None, None)
    assert capsys.readouterr().out.splitlines() == [
        "demo: 1 block (0.0 s of output), 1 deadline miss (worst 0.5 ms late), 1 clamped "
        "sample, 1 frame drawn "
        "(1.0 ms mean), link: closed",
        "demo: link: the device ran dry 1 time and 1 block was skipped to catch up; 0 of 5 "
        "samples unplayed; 0.00% held to --max-unplayed 10.00%, the skipped 0.00% to 50%"]


def test_the_demos_closing_line_says_which_unplayed_share_each_limit_holds(capsys):
    """The line split the unplayed samples by cause without saying that --max-unplayed
    holds only those not skipped to catch up (the skipped to half)."""
    from types import SimpleNamespace
    from frictex.app.commands.demo import _Ended, _print_lines
    summary = {"cpu_steal_pct": None, "blocks": 2524, "output_s": 6.3, "deadline_misses": 0,
               "worst_lateness_ms": 0.0, "clamps_total": 0, "frames": 1, "frame_ms_mean": 1.0,
               "input_counts": {}, "control": None, "ended_by": "window",
               "dropped_record_blocks": 0}
    link = {"state": "closed", "skipped_blocks": 96, "underruns": 2, "unplayed_samples": 2500,
            "commanded_samples": 63100, "unplayed_by_cause": {"skipped": 2400, "lost": 100}}
    _print_lines(SimpleNamespace(max_unplayed=0.001), summary,
                 _Ended(summary, link, None, None), None, None)
    assert capsys.readouterr().out.splitlines()[1] == (
        "demo: link: the device ran dry 2 times and 96 blocks were skipped to catch up; 2500 "
        "of 63100 samples unplayed, skipped 2400, lost 100; 0.16% held to --max-unplayed "
        "0.10%, the skipped 3.80% to 50%")


def test_blocks_left_out_of_a_recording_are_warned_of(capsys):
    """The recorder's queue full: the count was only a number in summary.json."""
    from frictex.app.commands.demo import _Ended, _print_lines
    summary = {"cpu_steal_pct": None, "blocks": 9, "output_s": 0.0, "deadline_misses": 0,
               "clamps_total": 0, "frames": 0, "frame_ms_mean": 0.0, "input_counts": {},
               "control": None, "ended_by": "window", "dropped_record_blocks": 3}
    _print_lines(None, summary, _Ended(summary, {"state": "none"}, None, None), None, None)
    assert capsys.readouterr().err == ("frictex demo: warning: 3 blocks were left out of the "
                                       "recording (its writer's queue was full): its tables "
                                       "miss them\n")

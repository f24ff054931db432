"""The demo's closing line gave only a count of deadline misses (a TUIO flood: "822
deadline misses", 533 ms late at worst, said nowhere but summary.json): it now says the
worst lateness beside the count."""

from frictex.app.commands.demo import _Ended, _print_lines


def closing_line(capsys, misses, worst_ms, steal_pct):
    summary = {"cpu_steal_pct": steal_pct, "blocks": 3573, "output_s": 8.9,
               "deadline_misses": misses, "worst_lateness_ms": worst_ms, "clamps_total": 0,
               "frames": 0, "frame_ms_mean": 0.0, "input_counts": {}, "control": None,
               "ended_by": "window", "dropped_record_blocks": 0}
    _print_lines(None, summary, _Ended(summary, {"state": "none"}, None, None), None, None)
    return capsys.readouterr().out.splitlines()[0]


def test_the_closing_line_says_the_worst_lateness_with_the_misses(capsys):
    line = closing_line(capsys, 822, 533.04, None)
    assert line.startswith("demo: 3573 blocks (8.9 s of output), 822 deadline misses "
                           "(worst 533.0 ms late), 0 clamped samples")


def test_the_worst_lateness_goes_with_the_cpu_steal(capsys):
    line = closing_line(capsys, 2, 3.0, 12.4)
    assert ", 2 deadline misses (worst 3.0 ms late; CPU steal by a VM host meanwhile: 12 %), " \
        in line


def test_no_miss_says_no_lateness_nor_steal(capsys):
    line = closing_line(capsys, 0, 0.0, 12.4)
    assert ", 0 deadline misses, 0 clamped samples" in line

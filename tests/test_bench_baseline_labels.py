"""``frictex bench baseline`` names the trace its reading verdict is on: --quick reads a
60 s trace, the full run a 600 s one, ten times the rows."""

from __future__ import annotations

import numpy as np
import pytest

from frictex.app.measure import bench_baseline


class _Stop(Exception):
    pass


@pytest.mark.parametrize("quick, name", [(True, "the 60 s trace (3,601 rows)"),
                                         (False, "the 600 s trace (36,001 rows)")])
def test_the_trace_reading_labels_give_the_traces_duration_and_rows(monkeypatch, quick, name):
    named = []

    def reading(path, reads=25, what="the trace"):
        named.append(what)
        raise _Stop

    monkeypatch.setattr(bench_baseline, "_reading_figures", reading)
    with pytest.raises(_Stop):
        bench_baseline.run(quick)
    assert named == [name]
    labels = [f.label for f in bench_baseline.reading_figures(
        np.array([2.0, 2.1]), np.array([1.0, 1.1]), name)]
    assert labels == [f"reading {name}, frictex read_trace (median of 2, alternated)",
                      f"reading {name}, pyarrow.csv.read_csv (median of 2, alternated)",
                      f"reading {name}, frictex against pyarrow, target at most 2x "
                      "(geometric mean of 2 rounds)"]


def test_the_module_says_how_many_lines_the_bare_program_has():
    lines = len(bench_baseline.BARE.strip().splitlines())
    assert f"The bare program has {lines} lines" in bench_baseline.__doc__

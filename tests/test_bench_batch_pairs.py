"""``frictex bench replay``'s batch pairs: a failed pair keeps the later pairs' numbers,
and the labels say how many runs and pairs failed."""

from __future__ import annotations

from frictex.app.measure import bench_replay
from frictex.app.measure.processes import Run


def _run(wall_s: float, code: int = 0) -> Run:
    return Run(wall_s, wall_s, 10.0, code)


def test_a_failed_pair_is_left_out_and_the_others_keep_their_numbers():
    one = [_run(10.0), _run(10.0, code=1), _run(12.0), _run(10.0)]
    many = [_run(5.0), _run(5.0), _run(6.0), _run(4.0)]
    labels = {f.label: f.value for f in bench_replay._batch_pair_figures(16, one, many, 4)}
    against = "batch throughput, 4 cores against one after another"
    assert {k: v for k, v in labels.items() if ", pair " in k} == {
        f"{against}, pair 1": 2.0, f"{against}, pair 3": 2.0, f"{against}, pair 4": 2.5}
    assert "batch of 16 one-minute jobs, one after another (median of 3, 1 of 4 failed)" in labels
    assert "batch of 16 one-minute jobs, 4 at once (median of 4)" in labels
    assert any(k.startswith(f"{against}, target at least 1.5x (geometric mean of 3 rounds, "
                            "1 of 4 failed)") for k in labels)

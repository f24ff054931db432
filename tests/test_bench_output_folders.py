"""Timed replays never write over each other's output: the one-second replay's runs
(bench replay) each start from a removed output folder, and bench startup gives every
replay command, the one without frictex's bytecode cache too, a folder of its own,
removed before each of its runs."""

from pathlib import Path

from frictex.app.measure import bench_replay, bench_startup
from frictex.app.measure.processes import Run


def _out(argv: list[str]) -> Path:
    return Path(argv[argv.index("--out") + 1])


def test_each_one_second_replay_starts_without_the_last_ones_output(monkeypatch, tmp_path):
    seen = []

    def fake_run(argv):
        out = _out(argv)
        seen.append((out.exists(), argv[argv.index("--format") + 1]))
        out.mkdir()  # what a replay leaves behind
        return Run(0.5, 0.4, 50.0, 0)

    monkeypatch.setattr(bench_replay, "run_process", fake_run)
    figure = bench_replay._one_second_figure(tmp_path, tmp_path / "one.csv", runs=3)
    assert seen == [(False, "csv")] * 3
    assert "to CSV" in figure.label and "one run after another" in figure.label


def test_every_startup_replay_has_its_own_output_folder_emptied_before_each_run(monkeypatch,
                                                                                 tmp_path):
    monkeypatch.setattr(bench_startup, "without_frictex_cache", lambda argv, prefix: argv)
    found, outputs = bench_startup.commands(tmp_path)
    replays = {name: _out(argv) for name, argv in found.items() if "--out" in argv}
    assert bench_startup.NO_CACHE in replays and len(replays) == 4
    assert len(set(replays.values())) == 4
    assert replays == outputs
    before = bench_startup.emptied(outputs)
    for name, out in replays.items():
        out.mkdir()
        before(name)
        assert not out.exists()
    before("frictex --version")  # no output folder: nothing to remove

"""frictex batch's output folder and batch.csv: an earlier batch's folders replaced,
anything else refused, each column counting what it says."""

import csv

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine.batch import MEASURES, RESULT_COLUMNS


def manifest(tmp_path, *names, trace="swipe-40mms-50hz"):
    path = tmp_path / f"m-{'-'.join(names)}.csv"
    path.write_text("scene,trace,name\n" + "".join(f"grating-5mm,{trace},{n}\n" for n in names))
    return path


def broken_trace(folder) -> None:
    """``folder/broken-trace.csv``: a file a job's replay refuses (the manifest's reading
    only checks that it is there)."""
    (folder / "broken-trace.csv").write_text("not,a,trace\n")


def batch(path, out, *extra) -> int:
    return main(["batch", str(path), "--out", str(out), "--jobs", "1", "--quiet", *extra])


def results(out):
    with open(out / "batch.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def listing(out):
    return sorted(p.name for p in out.iterdir())


def test_a_batch_replaces_an_earlier_batch_in_its_folder(tmp_path):
    """The review's case: p01-t1, t2, t4 from an earlier batch, then a batch of new1 and
    p01-t2: afterwards the folder holds batch.csv and the new batch's jobs, and p01-t2
    holds the new run (its summary replaced)."""
    out = tmp_path / "batch1"
    assert batch(manifest(tmp_path, "p01-t1", "p01-t2", "p01-t4"), out) == 0
    before = (out / "p01-t2" / "summary.json").stat().st_ino
    assert batch(manifest(tmp_path, "new1", "p01-t2"), out) == 0
    assert listing(out) == ["batch.csv", "new1", "p01-t2"]
    assert [row["name"] for row in results(out)] == ["new1", "p01-t2"]
    assert (out / "p01-t2" / "summary.json").stat().st_ino != before


def test_an_earlier_jobs_folder_goes_when_its_job_now_fails(tmp_path, capsys):
    """batch.csv lists the job failed: its earlier outputs are not left beside it as if
    they were this batch's."""
    out = tmp_path / "o"
    assert batch(manifest(tmp_path, "a", "b"), out) == 0
    broken_trace(tmp_path)
    broken = tmp_path / "m-broken.csv"
    broken.write_text("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\n"
                      "grating-5mm,broken-trace.csv,b\n")
    assert batch(broken, out) == 1
    assert listing(out) == ["a", "batch.csv"]
    assert {r["name"]: r["status"] for r in results(out)} == {"a": "ok", "b": "failed"}


@pytest.mark.parametrize("foreign", ["notes.txt", "data", "m.csv"])
def test_a_folder_holding_anything_else_is_refused_untouched(tmp_path, capsys, foreign):
    out = tmp_path / "o"
    assert batch(manifest(tmp_path, "a"), out) == 0
    if foreign == "data":
        (out / foreign).mkdir()
        (out / foreign / "x.csv").write_text("1\n")
    else:
        (out / foreign).write_text("mine\n")
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    assert batch(manifest(tmp_path, "b"), out) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f'holds "{foreign}", which is not an earlier batch' in err[0]
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before


def test_a_job_folder_with_the_users_file_is_kept_and_named(tmp_path, capsys):
    out = tmp_path / "o"
    assert batch(manifest(tmp_path, "a", "b"), out) == 0
    (out / "b" / "notes.txt").write_text("trial b went badly\n")
    assert batch(manifest(tmp_path, "a"), out) == 0
    assert "b: an earlier batch's job folder that also holds files" in capsys.readouterr().err
    assert sorted(p.name for p in (out / "b").iterdir()) == ["commands.csv", "friction.csv",
                                                              "notes.txt", "summary.json"]


def test_a_file_as_out_is_refused(tmp_path, capsys):
    (tmp_path / "o").write_text("")
    assert batch(manifest(tmp_path, "a"), tmp_path / "o") == 2
    assert "exists and is not a folder" in capsys.readouterr().err


def test_each_column_counts_what_it_says(tmp_path):
    """x_realtime is output_s / wall_s of the same row; the replay's end-to-end factor,
    which leaves the start-up out, is at least as large; a failed job's numeric cells
    are empty."""
    broken_trace(tmp_path)
    path = tmp_path / "m.csv"
    path.write_text("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,ok1\n"
                    "grating-5mm,broken-trace.csv,bad\n")
    assert batch(path, tmp_path / "o") == 1
    rows = {row["name"]: row for row in results(tmp_path / "o")}
    assert list(rows["ok1"]) == list(RESULT_COLUMNS)
    ok = {key: float(rows["ok1"][key]) for key in MEASURES}
    assert ok["output_s"] == pytest.approx(2.005)
    half = 0.5e-4  # the cells' rounding (4 decimals)
    assert (ok["output_s"] / (ok["wall_s"] + half) - half <= ok["x_realtime"]
            <= ok["output_s"] / (ok["wall_s"] - half) + half)
    assert ok["x_realtime_end_to_end"] >= ok["x_realtime"]
    assert all(rows["bad"][key] == "" for key in MEASURES)
    assert rows["bad"]["status"] == "failed" and rows["bad"]["error"]


def test_a_killed_jobs_staging_leftover_is_not_foreign(tmp_path):
    """What a killed replay of an earlier version left in a batch's folder is an earlier
    batch's output, not refused: gone with it when the next batch replaces the folder."""
    out = tmp_path / "o"
    assert batch(manifest(tmp_path, "a"), out) == 0
    leftover = out / ".a.frictex-staging.999999999.abcdef"
    leftover.mkdir()
    (leftover / "friction.csv").write_text("t_s\n")
    assert batch(manifest(tmp_path, "a"), out) == 0
    assert listing(out) == ["a", "batch.csv"]


def tree(folder):
    """Every file under ``folder`` with its bytes (batch.csv's wall times included)."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def test_a_batch_killed_midway_leaves_the_earlier_batch_whole(tmp_path):
    """SIGKILL while job b runs leaves --out byte for byte the earlier batch; the next
    batch clears the killed one's staging folder, b's replay's leftover in it included."""
    import subprocess
    import sys
    import time
    out = tmp_path / "o"
    assert batch(manifest(tmp_path, "a", "b"), out) == 0
    before = tree(out)
    long = tmp_path / "long.csv"
    assert main(["trace", "synth", "swipe", "--duration", "600", "--speed", "0.1",
                 "-o", str(long)]) == 0
    rerun = tmp_path / "m-rerun.csv"
    rerun.write_text("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\n"
                     f"grating-5mm,{long},b\n")
    proc = subprocess.Popen([sys.executable, "-m", "frictex", "batch", str(rerun), "--out",
                             str(out), "--jobs", "1", "--quiet"])
    deadline = time.monotonic() + 120.0
    staged = []
    while time.monotonic() < deadline and proc.poll() is None:
        staged = [p for p in tmp_path.glob(".o.frictex-staging.*")
                  if (p / "a").is_dir() and list(p.glob(".b.frictex-staging.*"))]
        if staged:  # job a has finished into the staging folder, b is running: kill now
            break
        time.sleep(0.05)
    proc.kill()
    proc.wait(timeout=60)
    assert staged, "the batch never got as far as its first job"
    assert tree(out) == before
    assert batch(manifest(tmp_path, "c"), out) == 0
    assert listing(out) == ["batch.csv", "c"]
    assert not list(tmp_path.glob(".o.frictex-*"))


def test_a_stopped_rerun_keeps_every_earlier_folder_it_did_not_replace(tmp_path, capsys,
                                                                          monkeypatch):
    """Ctrl-C during a rerun: the jobs that finished replace their folders, every earlier
    folder it did not replace is kept, and batch.csv lists it 'earlier' with the earlier
    figures (job empty where the new manifest does not name it)."""
    from frictex.app.commands import batch as command
    from frictex.app.engine.fanout import Interrupted
    out = tmp_path / "o"
    assert batch(manifest(tmp_path, "a", "b", "old"), out) == 0
    earlier_rows = results(out)
    # a's earlier wall time made one no run of it takes, so that this run's cannot equal it
    earlier_rows[0]["wall_s"] = "1234.5"
    with open(out / "batch.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(earlier_rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows(earlier_rows)
    earlier = {row["name"]: row for row in earlier_rows}
    b_summary = (out / "b" / "summary.json").read_bytes()
    real = command.fan_out

    def stopped_after_first(fn, items, **kwargs):
        first = real(fn, items[:1], workers=1)
        raise Interrupted(2, first + [None] * (len(items) - 1), [1])
    monkeypatch.setattr(command, "fan_out", stopped_after_first)
    assert batch(manifest(tmp_path, "a", "b", "new"), out) == 130
    assert listing(out) == ["a", "b", "batch.csv", "old"]
    rows = {row["name"]: row for row in results(out)}
    assert {name: (row["job"], row["status"]) for name, row in rows.items()} == {
        "a": ("0", "ok"), "b": ("1", "earlier"), "new": ("2", "interrupted"),
        "old": ("", "earlier")}
    assert rows["a"]["wall_s"] != "1234.5"  # this run's
    for name in ("b", "old"):
        assert {k: rows[name][k] for k in MEASURES} == {k: earlier[name][k] for k in MEASURES}
    assert (out / "b" / "summary.json").read_bytes() == b_summary
    assert "1 of 3 jobs finished" in capsys.readouterr().err

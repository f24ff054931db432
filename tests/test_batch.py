"""frictex batch: a manifest of replays over the cores or a Dask cluster on loopback."""

import csv
import unicodedata

import pytest
from hypothesis import given, settings, strategies as st

from frictex.app.commands.cli import main
from frictex.app.engine.batch import (MAX_ERROR_SHOWN, NAME, RESERVED, Job, ManifestError,
                                      read_manifest, run_job)
from frictex.device.errors import RunFailed
from frictex.rendering.input.trace_file import TraceError
from frictex.rendering.pipeline import RENDERERS

MANIFEST = """# a study's trials
scene,trace,renderer,name
grating-5mm,swipe-40mms-50hz,,five
grating-0.6mm,swipe-40mms-50hz,sht,fine
grating-5mm,broken-trace.csv,,broken
"""
#: a trace file a job's replay refuses (the manifest's reading only checks that it is there)
BROKEN_TRACE = "not,a,trace\n"


def write_manifest(folder, text=MANIFEST):
    """``text`` as ``folder/m.csv``, with the broken trace it names beside it."""
    (folder / "broken-trace.csv").write_text(BROKEN_TRACE)
    manifest = folder / "m.csv"
    manifest.write_text(text)
    return manifest


def rows(path):
    with open(path, newline="") as fh:
        return {r["name"]: r for r in csv.DictReader(fh)}


def test_a_broken_job_is_named_and_the_others_complete(tmp_path, capsys):
    manifest = write_manifest(tmp_path)
    assert main(["batch", str(manifest), "--out", str(tmp_path / "out"), "--jobs", "2",
                 "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "frictex: error: 1 of 3 jobs failed: broken: " in err
    results = rows(tmp_path / "out" / "batch.csv")
    assert {n: r["status"] for n, r in results.items()} == {"five": "ok", "fine": "ok",
                                                             "broken": "failed"}
    for name in ("five", "fine"):
        assert (tmp_path / "out" / name / "summary.json").exists()
        assert float(results[name]["output_s"]) == pytest.approx(2.005)
    assert not (tmp_path / "out" / "broken").exists()


def test_jobs_give_what_single_replays_give(tmp_path):
    manifest = tmp_path / "m.csv"
    manifest.write_text("scene,trace,renderer\ngrating-0.6mm,swipe-40mms-50hz,sht\n")
    assert main(["batch", str(manifest), "--out", str(tmp_path / "b"), "--jobs", "1",
                 "--quiet"]) == 0
    assert main(["replay", "grating-0.6mm", "swipe-40mms-50hz", "--renderer", "sht",
                 "--out", str(tmp_path / "r"), "--quiet"]) == 0
    job = tmp_path / "b" / "0000-grating-0.6mm-swipe-40mms-50hz"
    for name in ("commands.csv", "friction.csv"):
        assert (job / name).read_bytes() == (tmp_path / "r" / name).read_bytes()


def test_jobs_at_once_give_what_jobs_one_after_another_give(tmp_path):
    manifest = tmp_path / "m.csv"
    manifest.write_text(MANIFEST.replace("broken-trace.csv", "swipe-40mms-50hz"))
    for jobs in ("1", "2"):
        assert main(["batch", str(manifest), "--out", str(tmp_path / jobs), "--jobs", jobs,
                     "--quiet"]) == 0
    for name in ("five", "fine", "broken"):
        for table in ("commands.csv", "friction.csv"):
            assert ((tmp_path / "2" / name / table).read_bytes()
                    == (tmp_path / "1" / name / table).read_bytes())


def test_the_same_batch_on_a_dask_cluster_on_loopback(tmp_path):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed "
                                      "(pip install 'frictex[cluster]')")
    manifest = write_manifest(tmp_path)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        code = main(["batch", str(manifest), "--out", str(tmp_path / "out"),
                     "--scheduler", cluster.scheduler_address, "--quiet"])
    assert code == 1
    results = rows(tmp_path / "out" / "batch.csv")
    assert [results[n]["status"] for n in ("five", "fine", "broken")] == ["ok", "ok", "failed"]
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(tmp_path / "r"),
                 "--quiet"]) == 0
    assert ((tmp_path / "out" / "five" / "friction.csv").read_bytes()
            == (tmp_path / "r" / "friction.csv").read_bytes())


def test_an_unreachable_scheduler_is_one_line(tmp_path, capsys):
    pytest.importorskip("distributed", reason="dask.distributed is not installed")
    manifest = write_manifest(tmp_path)
    assert main(["batch", str(manifest), "--out", str(tmp_path / "o"),
                 "--scheduler", "tcp://127.0.0.1:9"]) == 1  # the cluster, not the input
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("frictex: error: cannot reach the Dask scheduler")


@pytest.mark.parametrize("address", ["nonsense", "tcp://127.0.0.1"])  # the port forgotten
def test_a_malformed_scheduler_address_is_one_line_and_bad_input(tmp_path, capsys, address):
    """distributed's ValueError ('missing port number') was an internal error, exit 70."""
    pytest.importorskip("distributed", reason="dask.distributed is not installed")
    manifest = write_manifest(tmp_path)
    assert main(["batch", str(manifest), "--out", str(tmp_path / "o"),
                 "--scheduler", address]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"frictex: error: --scheduler {address}: not a "
                                               "scheduler's address (")
    assert err[0].endswith("expected tcp://HOST:PORT")


@pytest.mark.parametrize("text, message", [
    ("", "no header and no jobs"),
    ("scene,trace\n", "a header but no jobs"),
    ("scene,colour\ngrating-5mm,red\n", "not a manifest header (2 fields: scene and colour)"),
    ("scene,trace,renderer\ngrating-5mm,swipe-40mms-50hz,fastest\n", 'renderer "fastest"'),
    ("scene,trace,rate_hz\ngrating-5mm,swipe-40mms-50hz,-3\n", 'rate_hz "-3"'),
    ("scene,trace,rate_hz\ngrating-5mm,swipe-40mms-50hz,nan\n", 'rate_hz "nan"'),
    ("scene,trace,format\ngrating-5mm,swipe-40mms-50hz,xlsx\n", 'format "xlsx"'),
    ("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,x\ngrating-5mm,swipe-40mms-50hz,x\n", 'name "x" is used by an earlier job'),
    ("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,../escape\n", "expected a plain folder name"),
    ("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,batch.csv\n", 'name "batch.csv" is a file the batch writes'),
    ("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,x\ngrating-5mm,swipe-40mms-50hz,Batch.CSV.partial\n",
     'name "Batch.CSV.partial" is a file the batch writes'),
    ("scene,trace\na\n", "1 fields, expected 2"),
])
def test_bad_manifests_name_the_line(tmp_path, capsys, text, message):
    manifest = tmp_path / "m.csv"
    manifest.write_text(text)
    assert main(["batch", str(manifest), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"frictex: error: {manifest}") and message in err[0]


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.text(alphabet=st.sampled_from("scenetracrdmfo_,.#\n\"'x0123456789-"), max_size=200))
def test_any_manifest_text_is_jobs_or_one_clear_error(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("m") / "m.csv"
    path.write_text(text)
    try:
        jobs = read_manifest(path, ("sho", *RENDERERS))
    except ManifestError as exc:
        assert str(exc).startswith(str(path)) and "\n" not in str(exc)
    else:
        assert jobs and len({j.name for j in jobs}) == len(jobs)


UNSAFE = {"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"}
_FIELDS = st.sampled_from(["grating-5mm", "swipe-40mms-50hz", "5e-324", "1e4", "\u0661\u0660",
                           "10_000", "50", "0", "csv", "sht", "../x", "a\x1bb", '"', ",", "\n",
                           "\r", "#", " ", "\u202e", "n" * 70, "name", "rate_hz", "block",
                           "batch.csv", "BATCH.csv.partial"])


@settings(max_examples=200, derandomize=True, deadline=None)
@given(st.one_of(st.lists(_FIELDS, max_size=30).map(lambda parts: "scene,trace,rate_hz,block,name\n"
                                                    + "".join(parts)),
                 st.text(max_size=200)))
def test_any_manifest_is_bounded_jobs_or_one_escaped_line(tmp_path_factory, text):
    """Any text: jobs within the command line's bounds whose names are plain folder
    names, or one ManifestError line naming the file, without a control character."""
    path = tmp_path_factory.mktemp("m") / "m.csv"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        jobs = read_manifest(path, ("sho", *RENDERERS))
    except ManifestError as exc:
        message = str(exc)
        assert message.startswith(str(path)) and not any(
            unicodedata.category(ch) in UNSAFE for ch in message), ascii(message)
    else:
        for job in jobs:
            assert 100 <= job.rate_hz <= 1e6 and 1 <= job.block <= 100_000
            assert NAME.fullmatch(job.name) and job.name not in (".", "..")
            assert job.name.casefold() not in RESERVED


@pytest.mark.parametrize("error", [RunFailed, TraceError, OSError])
def test_a_job_error_is_an_escaped_cut_cell(monkeypatch, tmp_path, error):
    """Whatever a job raises of frictex's kinds (or ValueError, OSError): a failed row
    whose error is one escaped line of at most MAX_ERROR_SHOWN characters."""
    from frictex.app.engine import replay

    def fail(*args, **kwargs):
        raise error("bad\x1b[2J\nline" + "x" * 1000)

    monkeypatch.setattr(replay, "run_replay", fail)
    row = run_job(Job(0, "grating-5mm", "swipe-40mms-50hz", None, 1e4, 50, "csv", "j"),
                  str(tmp_path))
    assert row["status"] == "failed" and row["error"].startswith("bad\\x1b[2J\\nlinexxx")
    assert len(row["error"]) == MAX_ERROR_SHOWN and row["error"].isprintable()


def test_a_value_the_reader_escaped_is_not_escaped_again(monkeypatch, tmp_path):
    """A scene whose layer type held ESC: batch.csv showed "\\x1b[31mgrat", where
    validate shows "\x1b[31mgrat" (the reader escaped it; the row escaped it again)."""
    from frictex.app.engine import replay
    from frictex.device.safe_text import quoted

    def fail(*args, **kwargs):
        raise TraceError(f"scene.toml:9: layer[1].type: {quoted(chr(27) + '[31mgrat')}")

    monkeypatch.setattr(replay, "run_replay", fail)
    row = run_job(Job(0, "grating-5mm", "swipe-40mms-50hz", None, 1e4, 50, "csv", "j"),
                  str(tmp_path))
    assert row["error"] == 'scene.toml:9: layer[1].type: "\\x1b[31mgrat"'


@pytest.mark.parametrize("scene", ['=HYPERLINK("http://x","y")', "@SUM(A1:A2)", "+1+2",
                                   "-2+3"])
def test_error_cells_never_start_a_formula(monkeypatch, tmp_path, scene):
    """An error that starts with the scene name as written is stored behind a single
    quote (OWASP): read back, no text cell starts with = + - @ tab or CR."""
    import csv
    from frictex.app.engine import replay
    from frictex.app.engine.batch import write_results

    def fail(scene_name, *args, **kwargs):
        raise TraceError(f"{scene_name}: no such scene")

    monkeypatch.setattr(replay, "run_replay", fail)
    rows = [run_job(Job(0, scene, "t", None, 1e4, 50, "csv", "j"), str(tmp_path))]
    with open(write_results(tmp_path, rows), encoding="utf-8", newline="") as fh:
        header, *cells = list(csv.reader(fh))
    error = cells[0][header.index("error")]
    assert error.startswith("'") and error[1:] == rows[0]["error"]
    assert not any(c.startswith(("=", "+", "-", "@", "\t", "\r")) for row in cells for c in row)


def test_cells_starting_with_tab_or_cr_are_quoted_too(tmp_path):
    """Errors reach batch.csv escaped (a tab as the two characters \\t), but any text
    cell written that starts with a tab or a carriage return is quoted as well; numbers
    are numbers."""
    import csv
    from frictex.app.engine.batch import RESULT_COLUMNS, write_results
    rows = [{name: "" for name in RESULT_COLUMNS} | {"error": start + "=1+1", "status": "failed"}
            for start in ("\t", "@", "=", "ok")]
    with open(write_results(tmp_path, rows), encoding="utf-8", newline="") as fh:
        errors = [row[RESULT_COLUMNS.index("error")] for row in list(csv.reader(fh))[1:]]
    assert errors == ["'\t=1+1", "'@=1+1", "'==1+1", "ok=1+1"]
    from frictex.app.engine.batch import _cell
    assert _cell("\r=1") == "'\r=1" and _cell(-1.5) == "-1.5000" and _cell(3) == 3


def test_a_trace_or_scene_that_is_no_regular_file_is_a_problem_of_the_manifest(tmp_path):
    """A trace that was a FIFO or a folder passed the manifest's check: the other jobs ran
    and that one failed. Every such cell is a problem of its line, and nothing runs."""
    import os
    os.mkfifo(tmp_path / "fifo.csv")
    (tmp_path / "dir.csv").mkdir()
    (tmp_path / "scene.toml").mkdir()
    path = tmp_path / "m.csv"
    path.write_text("scene,trace\ngrating-5mm,fifo.csv\ngrating-5mm,dir.csv\n"
                    "scene.toml,swipe-40mms-50hz\ngrating-5mm,swipe-40mms-50hz\n")
    with pytest.raises(ManifestError) as caught:
        read_manifest(path, ("sho", *RENDERERS))
    assert list(caught.value.error_lines) == [f"{path}:{line}" for line in (
        '2: trace "fifo.csv": is a FIFO (named pipe), not a regular file (frictex reads '
        'only regular files); expected a trace CSV file',
        '3: trace "dir.csv": is a folder, not a file; expected a trace CSV file',
        '4: scene "scene.toml": is a folder, not a file; expected a texture file')]

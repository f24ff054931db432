"""A replay's output folder holds a whole run, the previous or the new, whatever ends it.

Replays are killed (SIGKILL, SIGTERM, SIGINT) at random moments of their run, seeded; after
each the folder must hold exactly the outputs of the previous run or of the new one, and
the next run removes whatever the killed one left beside it. Ctrl-C ends a run with one
line and exit 130 (never numba's SystemError). Then the refusals: disk room (frames
counted) on a small tmpfs, a folder it could not replace whole.
"""

import json
import os
import random
import select
import shutil
import signal
import socket
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from frictex.app.commands.cli import main

SCENE = "grating-5mm"
TRACES = ("swipe-40mms-50hz", "circle-30mms-60hz")  # the two runs that replace each other
KILLS = 20
LEFTOVERS = "removed the leftovers of"


def replay(out: Path, trace: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "frictex", "replay", SCENE, trace, "--out",
                             str(out), "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def contents(folder: Path) -> dict:
    """The folder's files (paths under it -> bytes), summary.json without its timings and
    the warning about leftovers (which differ between two runs of the same inputs)."""
    found = {}
    for path in sorted(folder.rglob("*")):
        if path.is_file():
            found[str(path.relative_to(folder))] = path.read_bytes()
    if "summary.json" in found:
        doc = json.loads(found["summary.json"])
        doc.pop("timings", None)
        doc["warnings"] = [w for w in doc.get("warnings", []) if not w.startswith(LEFTOVERS)]
        found["summary.json"] = doc
    return found


def beside(folder: Path) -> list[str]:
    """What is beside ``folder`` in its parent (a killed run's staging folder, if any)."""
    return sorted(p.name for p in folder.parent.iterdir() if p.name != folder.name)


@pytest.fixture(scope="module")
def references(tmp_path_factory):
    """Each trace's complete run, and the wall time of one (s)."""
    found, wall = {}, 0.0
    for trace in TRACES:
        out = tmp_path_factory.mktemp("ref") / "out"
        t0 = time.monotonic()
        run = replay(out, trace)
        assert run.wait(timeout=300) == 0, run.stderr.read()
        wall = max(wall, time.monotonic() - t0)
        found[trace] = contents(out)
    return found, wall


def test_a_killed_run_leaves_the_previous_run_or_the_new_one(tmp_path, references):
    runs, wall = references
    out = tmp_path / "out"
    first = replay(out, TRACES[0])
    assert first.wait(timeout=300) == 0
    rng = random.Random(7)
    signals = (signal.SIGKILL, signal.SIGTERM, signal.SIGINT)
    held, mid_write = TRACES[0], 0
    for i in range(KILLS):
        trace = TRACES[(TRACES.index(held) + 1) % 2]
        run = replay(out, trace)
        def staging():
            return list(tmp_path.glob(f".{out.name}.frictex-staging.{run.pid}.*"))
        if i % 2:  # any moment of the run, start-up included
            time.sleep(rng.uniform(0.0, wall * 1.2))
        else:  # a moment after it began writing into its staging folder
            while not staging() and run.poll() is None:
                time.sleep(0.005)
            time.sleep(rng.uniform(0.0, 0.3))
        mid_write += bool(staging())
        sig = signals[i % 3]
        run.send_signal(sig)
        code = run.wait(timeout=120)
        err = run.stderr.read()
        assert "SystemError" not in err
        if sig == signal.SIGINT and code == 130:
            assert err.strip().splitlines() == ["frictex: interrupted"]
        now = contents(out)
        assert now in (runs[held], runs[trace]), f"kill {i} ({sig.name}) left a mix"
        held = trace if now == runs[trace] else held
    assert mid_write > 0  # some kills came while a run was writing (else this proved less)
    # the next run removes what killed runs left beside the folder, and says so
    left = beside(out)
    final = replay(out, TRACES[0])
    assert final.wait(timeout=300) == 0
    assert beside(out) == []
    assert contents(out) == runs[TRACES[0]]
    warned = [w for w in json.loads((out / "summary.json").read_text())["warnings"]
              if w.startswith(LEFTOVERS)]
    assert bool(warned) == bool(left)


def test_frames_of_an_earlier_run_go_with_it(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet", "--frames", "2"]) == 0
    assert list((out / "frames").glob("frame_*.png"))
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["commands.csv", "friction.csv",
                                                     "summary.json"]


def test_a_folder_a_run_cannot_replace_whole_is_refused_untouched(tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    (out / "notes").mkdir(parents=True)
    (out / "mine.txt").write_text("kept")
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 2
    assert "holds the folder 'notes'" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["mine.txt", "notes"]
    (out / "notes").rmdir()
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 0
    assert (out / "mine.txt").read_text() == "kept"  # not a run's: carried over
    monkeypatch.chdir(out)
    assert main(["replay", SCENE, TRACES[0], "--out", ".", "--quiet"]) == 2
    assert "holds the current folder" in capsys.readouterr().err
    assert beside(out) == []


@pytest.fixture
def small_disk(tmp_path):
    """A 5 MB tmpfs (root only)."""
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    disk = tmp_path / "disk"
    disk.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=5m", "tmpfs", str(disk)],
                          capture_output=True, text=True)
    if done.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()}")
    yield disk
    subprocess.run(["umount", str(disk)], check=True)


def fill(disk: Path) -> None:
    """Fill ``disk`` to the last byte."""
    for name, size in (("filler", 65536), ("filler-tail", 1)):
        fd = os.open(disk / name, os.O_WRONLY | os.O_CREAT)
        try:
            while os.write(fd, b"\0" * size):
                pass
        except OSError:
            pass
        finally:
            os.close(fd)


def test_a_replay_refused_for_room_touches_nothing(small_disk, capsys):
    out = small_disk / "out"
    out.mkdir()
    (out / "commands.csv").write_text("an earlier run\n")
    (out / "summary.json").write_text("{}\n")
    before = contents(out)
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the outputs (" in err[0] and "is free" in err[0]
    assert contents(out) == before and beside(out) == []
    assert main(["replay", SCENE, TRACES[0], "--out", str(small_disk), "--quiet"]) == 2
    assert "a mount point" in capsys.readouterr().err


def test_frames_are_counted_in_the_room_check(small_disk, monkeypatch, capsys):
    from frictex.app.engine import tables
    monkeypatch.setattr(tables, "RESERVE_BYTES", 0)
    out = small_disk / "out"
    argv = ["replay", SCENE, TRACES[0], "--out", str(out), "--quiet", "--rate", "2000"]
    assert main(argv + ["--frames", "100"]) == 1
    err = capsys.readouterr().err
    assert "frames at 100 fps" in err and "is free" in err
    assert sorted(p.name for p in small_disk.iterdir()) == []
    assert main(argv) == 0  # the tables alone fit


@pytest.mark.parametrize("command", [
    ["trace", "synth", "swipe", "--duration", "5", "-o"],
    ["preview", SCENE, "-o"],
])
@pytest.mark.parametrize("checked", [True, False], ids=["room-checked", "disk-fills-while-writing"])
def test_a_full_disk_leaves_the_earlier_file_and_names_it(small_disk, monkeypatch, capsys,
                                                          command, checked):
    from frictex.app.engine import outfile, tables
    monkeypatch.setattr(tables, "RESERVE_BYTES", 0)
    if not checked:  # the estimate let it through: the write itself meets the full disk
        monkeypatch.setattr(outfile, "check_room", lambda *args: None)
    target = small_disk / ("out.csv" if command[0] == "trace" else "out.png")
    target.write_bytes(b"an earlier file")
    fill(small_disk)
    assert main(command + [str(target)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and target.name in err[0]
    assert target.read_bytes() == b"an earlier file"
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler", "filler-tail", target.name]


def dead_pid() -> int:
    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    return int(done.stdout)


def test_without_an_atomic_exchange_two_renames_and_a_recovery(tmp_path, monkeypatch):
    """Where the file system cannot exchange two folders: --out is renamed aside, then the
    staging folder in; a run killed between the two leaves no --out, and the next run puts
    the previous one back before it starts."""
    from frictex.app.engine import staging
    monkeypatch.setattr(staging, "_exchange", lambda a, b: False)
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("old")
    (out / "mine.txt").write_text("kept")
    run = staging.Staging(out)
    (run.begin() / "summary.json").write_text("new")
    run.commit()
    assert {p.name: p.read_text() for p in out.iterdir()} == {"summary.json": "new",
                                                               "mine.txt": "kept"}
    assert beside(out) == []
    out.rename(tmp_path / f".out.frictex-old.{dead_pid()}.0a1b")  # killed between the renames
    (tmp_path / f".out.frictex-staging.{dead_pid()}.2c3d").mkdir()
    again = staging.Staging(out)
    again.begin()
    assert (out / "summary.json").read_text() == "new"
    assert beside(out) == [again.folder.name]
    again.abort()
    assert beside(out) == []


def test_an_output_folder_named_by_a_link_is_replaced_where_it_is(tmp_path, capsys):
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to("real")
    for _ in range(2):
        assert main(["replay", SCENE, TRACES[0], "--out", str(tmp_path / "link"), "--quiet"]) == 0
    assert (tmp_path / "link").is_symlink()
    assert sorted(p.name for p in (tmp_path / "real").iterdir()) == [
        "commands.csv", "friction.csv", "summary.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "real"]


def test_only_the_names_a_run_writes_are_its_own(tmp_path, capsys):
    """A folder or file whose name merely starts like a table's is the user's: a folder is
    refused untouched, a file carried over; so is a frames folder with a file of theirs."""
    out = tmp_path / "out"
    (out / "friction.backup").mkdir(parents=True)
    (out / "friction.backup" / "data.txt").write_text("x")
    (out / "commands.notes.txt").write_text("n")
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 2
    assert "holds the folder 'friction.backup'" in capsys.readouterr().err
    assert (out / "friction.backup" / "data.txt").read_text() == "x"
    shutil.rmtree(out / "friction.backup")
    (out / "frames").mkdir()
    (out / "frames" / "mine.txt").write_text("f")
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 2
    assert "holds the folder 'frames'" in capsys.readouterr().err
    assert (out / "frames" / "mine.txt").read_text() == "f"
    (out / "frames" / "mine.txt").unlink()
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["commands.csv", "commands.notes.txt",
                                                     "friction.csv", "summary.json"]
    assert (out / "commands.notes.txt").read_text() == "n"
    assert beside(out) == []


def test_a_folder_made_in_out_during_the_run_fails_it_and_is_kept(tmp_path, monkeypatch, capsys):
    from frictex.app.engine import staging
    out = tmp_path / "out"
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 0
    before = contents(out)
    begin = staging.Staging.begin

    def begin_then_a_folder_appears(self):
        folder = begin(self)
        (out / "late").mkdir()
        (out / "late" / "data.txt").write_text("x")
        return folder

    monkeypatch.setattr(staging.Staging, "begin", begin_then_a_folder_appears)
    assert main(["replay", SCENE, TRACES[1], "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'late'" in err[0] and "nothing was replaced" in err[0]
    assert (out / "late" / "data.txt").read_text() == "x"
    (out / "late" / "data.txt").unlink()
    (out / "late").rmdir()
    assert contents(out) == before and beside(out) == []


def test_a_file_that_appears_during_the_swap_is_moved_into_the_new_run(tmp_path, monkeypatch):
    from frictex.app.engine import staging
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("old")
    run = staging.Staging(out)
    (run.begin() / "summary.json").write_text("new")
    exchange = staging._exchange

    def a_file_appears_first(a, b):
        (b / "late.txt").write_text("x")  # after the carry, before the swap
        return exchange(a, b)

    monkeypatch.setattr(staging, "_exchange", a_file_appears_first)
    run.commit()
    assert {p.name: p.read_text() for p in out.iterdir()} == {"summary.json": "new",
                                                               "late.txt": "x"}
    assert beside(out) == []


def test_two_runs_of_one_process_into_one_folder_have_their_own_staging(tmp_path):
    from frictex.app.engine import staging
    out = tmp_path / "out"
    first, second = staging.Staging(out), staging.Staging(out)
    (first.begin() / "summary.json").write_text("first")
    (second.begin() / "summary.json").write_text("second")
    assert first.folder != second.folder and first.folder.exists()
    third = staging.Staging(out)
    third.begin()  # its recovery leaves the other two alone: this process still owns them
    first.commit()
    assert (out / "summary.json").read_text() == "first"
    second.commit()
    assert (out / "summary.json").read_text() == "second"
    third.abort()
    assert beside(out) == [] and third.removed == []


def test_the_root_folder_is_bad_input(capsys):
    import frictex
    assert main(["replay", SCENE, TRACES[0], "--out", "/", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the root folder" in err[0]
    with pytest.raises(frictex.InputError, match="the root folder"):
        frictex.replay(SCENE, TRACES[0], out="/")


def test_an_output_folder_under_a_file_is_bad_input_naming_the_file(tmp_path, capsys):
    (tmp_path / "a-file").write_text("kept")
    out = tmp_path / "a-file" / "deeper" / "out"
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"frictex: error: {out}: {tmp_path / 'a-file'} is not a folder, so no folder "
                   "can be made in it"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file"]


@pytest.mark.skipif(not os.path.ismount("/proc"), reason="no /proc file system mounted")
def test_an_output_folder_on_a_file_system_of_no_size_is_bad_input(capsys):
    """/proc holds no files: it was 'need about 1.85 MB and 0 B is free' (exit 1)."""
    import frictex
    assert main(["replay", SCENE, TRACES[0], "--out", "/proc/frictex-out", "--quiet"]) == 2
    assert capsys.readouterr().err == ("frictex: error: /proc: a file system that holds no "
                                       "files (such as /proc or /sys); write the outputs "
                                       "elsewhere\n")
    with pytest.raises(frictex.InputError, match="holds no files"):
        frictex.replay(SCENE, TRACES[0], out="/proc/frictex-out")


def test_the_output_folder_keeps_its_permissions_and_attributes(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    out.chmod(0o710)
    try:
        os.setxattr(out, "user.note", b"mine")
        xattr = True
    except OSError:  # a file system without user attributes
        xattr = False
    for trace in TRACES:
        assert main(["replay", SCENE, trace, "--out", str(out), "--quiet"]) == 0
        assert out.stat().st_mode & 0o7777 == 0o710
        if xattr:
            assert os.getxattr(out, "user.note") == b"mine"


def test_a_long_folder_name_fits_its_staging_name(tmp_path):
    out = tmp_path / ("a" * 240)
    for trace in TRACES:
        assert main(["replay", SCENE, trace, "--out", str(out), "--quiet"]) == 0
    assert (out / "summary.json").exists() and beside(out) == []


@pytest.fixture
def mounted(tmp_path):
    """Mount with ``mount ARGS...`` (root only); unmounted after the test."""
    if os.geteuid() != 0:
        pytest.skip("mounting needs root")
    points = []

    def mount(*args: str) -> None:
        done = subprocess.run(["mount", *args], capture_output=True, text=True)
        if done.returncode:
            pytest.skip(f"cannot mount here: {done.stderr.strip()}")
        if args[-1] not in points:
            points.append(args[-1])

    yield mount
    for point in reversed(points):
        subprocess.run(["umount", point], check=True)


def test_a_bind_mount_is_refused_as_a_mount_point(tmp_path, mounted, capsys):
    (tmp_path / "real").mkdir()
    (tmp_path / "bound").mkdir()
    mounted("--bind", str(tmp_path / "real"), str(tmp_path / "bound"))
    assert main(["replay", SCENE, TRACES[0], "--out", str(tmp_path / "bound"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a mount point" in err[0]
    assert list((tmp_path / "real").iterdir()) == []


def test_an_error_on_the_staging_folder_names_the_output_folder(tmp_path, mounted, capsys):
    parent = tmp_path / "ro"
    parent.mkdir()
    mounted("--bind", str(parent), str(parent))
    mounted("-o", "remount,ro,bind", str(parent))
    assert main(["replay", SCENE, TRACES[0], "--out", str(parent / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{parent / 'out'}: cannot" in err[0]
    assert "frictex-staging" not in err[0]


def test_a_ctrl_c_during_the_commit_reports_the_complete_run(tmp_path, monkeypatch, capsys):
    """Once the swap has begun the run cannot be stopped: Ctrl-C then (twice) is held and
    the run reports success, as --out holds the whole new run."""
    from frictex.app.engine import staging
    out = tmp_path / "out"
    commit = staging.Staging.commit

    def commit_under_ctrl_c(self):
        os.kill(os.getpid(), signal.SIGINT)
        commit(self)
        os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(staging.Staging, "commit", commit_under_ctrl_c)
    assert main(["replay", SCENE, TRACES[0], "--out", str(out), "--quiet"]) == 0
    assert "interrupted" not in capsys.readouterr().err
    assert json.loads((out / "summary.json").read_text())["output"]["samples"] > 0


def test_signals_during_a_stopped_runs_cleanup_do_not_cut_it_short(tmp_path):
    """A run stopped by Ctrl-C aborts every sink and removes its staging folder even when
    more signals come meanwhile (a batch worker whose parent dies gets one for each of
    the parent's threads): the first attached sink gets two more in its abort, and the
    second is still aborted, nothing is left beside --out."""
    from frictex.app.engine.replay import run_replay

    class Sink:
        def __init__(self, signals_in_abort: int):
            self.blocks, self.signals, self.aborted = 0, signals_in_abort, False

        def write(self, out, commands):
            self.blocks += 1
            if self.blocks == 3 and self.signals:
                os.kill(os.getpid(), signal.SIGINT)

        def commit(self):
            pass

        def abort(self):
            for _ in range(self.signals):
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.02)
            self.aborted = True

    signalled, quiet = Sink(2), Sink(0)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_replay(SCENE, TRACES[0], out, chunk_blocks=1, sinks=[signalled, quiet])
    assert signalled.aborted and quiet.aborted
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_a_link_is_written_through_and_stays_a_link(tmp_path):
    (tmp_path / "real.csv").write_text("earlier")
    (tmp_path / "link.csv").symlink_to("real.csv")
    assert main(["trace", "synth", "swipe", "--duration", "1", "-o",
                 str(tmp_path / "link.csv")]) == 0
    assert (tmp_path / "link.csv").is_symlink()
    assert (tmp_path / "real.csv").read_text().count("\n") > 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.csv", "real.csv"]


def test_a_device_node_is_written_not_replaced(tmp_path):
    if os.geteuid() != 0:
        pytest.skip("making a device node needs root")
    null = tmp_path / "null"
    os.mknod(null, 0o666 | stat.S_IFCHR, os.makedev(1, 3))  # what /dev/null is
    assert main(["trace", "synth", "swipe", "--duration", "1", "-o", str(null)]) == 0
    assert stat.S_ISCHR(os.lstat(null).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["null"]


def test_a_fifo_is_written_into_not_replaced(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # open now: the writer never waits
    got = bytearray()
    done = threading.Event()

    def read():
        while not done.is_set():
            ready, _, _ = select.select([reader], [], [], 0.05)
            if ready:
                got.extend(os.read(reader, 1 << 16))

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    try:
        assert main(["trace", "synth", "swipe", "--duration", "1", "-o", str(fifo)]) == 0
    finally:
        done.set()
        thread.join(timeout=10)
        try:  # what the reader thread had no turn to read before the writer finished
            while chunk := os.read(reader, 1 << 16):
                got.extend(chunk)
        except BlockingIOError:
            pass
        os.close(reader)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert bytes(got).startswith(b"#") or b"t_s" in bytes(got)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo"]


def test_a_folder_or_socket_as_an_output_file_is_one_line(tmp_path, capsys):
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(tmp_path / "sock"))
    try:
        for target, what in ((tmp_path, "is a folder"), (tmp_path / "sock", "is a socket")):
            assert main(["trace", "synth", "swipe", "--duration", "1", "-o", str(target)]) == 2
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and what in err[0]
    finally:
        sock.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sock"]


def test_an_out_another_run_creates_just_before_the_commit_is_replaced(tmp_path, monkeypatch):
    """Two batches into one new --out: the other committed between this commit's look
    for --out and its rename. Before, the rename onto the other's folder failed with
    'Directory not empty'; now that folder is replaced as any previous run's."""
    from frictex.app.engine import staging
    out = tmp_path / "out"
    first, second = staging.Staging(out), staging.Staging(out)
    (first.begin() / "summary.json").write_text("first")
    (second.begin() / "summary.json").write_text("second")
    exists = Path.exists

    def the_other_commits_meanwhile(path):
        found = exists(path)
        if path == out and not found:
            monkeypatch.setattr(Path, "exists", exists)
            first.commit()
        return found

    monkeypatch.setattr(Path, "exists", the_other_commits_meanwhile)
    second.commit()
    assert {p.name: p.read_text() for p in out.iterdir()} == {"summary.json": "second"}
    assert beside(out) == []

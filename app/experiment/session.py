"""The session folder: what a session ran, trial by trial, safe against a killed process.

::

    DIR/session.json          what ran: protocol name, method, seed, participant (who
                              answered: window or simulated:...), participant_seed
                              (the seed a simulated participant answered with, else
                              null), participant_id (the person's code, or null),
                              versions (frictex, python, numpy, scipy, platform),
                              record (what is kept per trial: all, traces or
                              results; ``--resume`` goes on with it), started_utc,
                              ended_utc (null until the last trial is
                              answered), parts (one per run of the session: its start,
                              end and trials; a part without an end was killed), and
                              the design the analysis needs (its vary_unit: the
                              unit of vary, value and difference); scene_sha256: each
                              scene file's sha256, by its name (``scene_files``),
                              checked by ``--resume``; every key a reader uses is
                              checked where the file is read (``session_schema``)
    DIR/protocol.toml         the protocol file as it was read
    DIR/NAME.toml             the protocol's scenes in its folder or below, copied under
                              the same relative names (``copy_scenes``), so that
                              DIR/protocol.toml resumes the session from DIR alone
    DIR/results.csv           one row per trial answered (RESULT_COLUMNS, each described
                              in PROTOCOL_FORMAT.md), in order;
                              contact_1_s, contact_2_s: how long each interval was
                              touched (s, finger down; empty for an interval the trial
                              has not). A table from before those two columns is read,
                              and resumed, in its own columns
    DIR/stimuli/NAME.toml     each stimulus's scene, as a texture file
    DIR/trials/NNNN/I.toml    the scene of interval I (1, 2) of trial NNNN ...
    DIR/trials/NNNN/I.csv     ... the touch trace over it (trace format) ...
    DIR/trials/NNNN/I/        ... and the replay of the two: commands.csv (what was sent to
                              the device), friction.csv, summary.json

``frictex replay DIR/trials/0007/1.toml DIR/trials/0007/1.csv --out X`` plays interval 1
of trial 7 again and writes the same commands.

Crash safety. A trial's files are written and synced first; then its row is appended to
``results.csv`` in one write and synced (``os.fsync``): the row is what makes the trial
count. A session killed at any point therefore holds every answered trial and at most the
files of one trial without its row; ``--resume`` drops those (and a row cut short by a
power loss, which has no line end), rebuilds the scheduler's state by answering the rows
again (``scheduler.Scheduler.replay``, which also checks that they are this protocol's and
seed's trials) and goes on with the next trial.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import os
import platform
import shutil
import tomllib
from dataclasses import asdict, dataclass
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

import numpy as np

from frictex.app.experiment.session_schema import check_info
from frictex.device.errors import InputError

FORMAT = 1
RESULT_COLUMNS = ("trial", "practice", "stimuli", "value", "difference", "answer", "response",
                  "correct", "rt_s", "ended_utc", "contact_1_s", "contact_2_s")
#: the columns of a results table written before the contact times
COLUMNS_BEFORE_CONTACT = RESULT_COLUMNS[:-2]
#: the separator between the stimuli of a trial in the ``stimuli`` column
SEPARATOR = "|"
#: what a session keeps per trial unless told (and what one whose session.json does not
#: record it, written before ``record`` was, kept)
DEFAULT_RECORD = "all"


def _sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def scene_files(protocol) -> dict[str, Path]:
    """The scene files ``protocol``'s stimuli are made from, by the name session.json
    keeps them under: a bundled scene by its file name, any other by its path relative
    to the protocol's folder (``myg.toml``, ``scenes/a.toml``)."""
    s = protocol.stimuli
    paths = ([s.scene] if s.scene is not None else []) + [st.scene for st in s.listed]
    return {Path(path).name if _bundled(path)
            else Path(os.path.relpath(path, protocol.source.parent)).as_posix(): Path(path)
            for path in paths}


def _bundled(path: Path) -> bool:
    """Whether the scene file ``path`` is one of frictex's library."""
    from frictex.textures.library import LIBRARY_DIR
    return Path(os.path.realpath(path)).is_relative_to(LIBRARY_DIR)


def scene_hashes(protocol) -> dict[str, str]:
    """sha256 of each of :func:`scene_files`, by its name."""
    return {key: _sha256(path) for key, path in scene_files(protocol).items()}


#: the names a session folder keeps for itself: a scene of one of these is not copied in
SESSION_NAMES = ("protocol.toml", "session.json", "results.csv", "stimuli", "trials",
                 "analysis")


def copy_scenes(folder: Path, protocol) -> None:
    """Copy the protocol's own scenes (those in its folder or below, with the files they
    name) into the session folder under the same relative names, so that the session's
    copy ``protocol.toml`` finds them: a session resumes from its own folder."""
    from frictex.app.experiment.stimuli import place_files
    for key, path in scene_files(protocol).items():
        parts = Path(key).parts
        if _bundled(path) or ".." in parts or Path(key).is_absolute() or parts[0] in SESSION_NAMES:
            continue
        target = folder / key
        target.parent.mkdir(parents=True, exist_ok=True)
        if os.path.realpath(path) != os.path.realpath(target):
            shutil.copyfile(path, target)
        place_files(tomllib.loads(target.read_text(encoding="utf-8")),
                    Path(os.path.realpath(path)).parent, target.parent)


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _write_synced(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file, synced, then renamed."""
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def _fsync_tree(folder: Path) -> None:
    for root, _, files in os.walk(folder):
        for name in files:
            fd = os.open(os.path.join(root, name), os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        _fsync_dir(Path(root))


def _number(value) -> str:
    if value is None:
        return ""
    return f"{value:.12g}" if isinstance(value, float) else str(value)


def contact_s(trace) -> float:
    """How long ``trace`` (a ``trace_file.Trace``) had a finger down (s): per finger, the
    time from each of its samples but an up to its next sample, summed over the fingers."""
    from frictex.rendering.input.trace_file import UP
    total = 0.0
    for finger in np.unique(trace.finger):
        mine = trace.finger == finger
        total += float(np.diff(trace.t_s[mine])[trace.event[mine][:-1] != UP].sum())
    return total


def result_row(trial, response: str, rt_s: float, traces=()) -> dict:
    """The results row of ``trial`` (a ``scheduler.Trial``) answered ``response``;
    ``traces``: what each interval was touched with (``trace_file.Trace``), for the
    contact times (none: empty)."""
    correct = "" if trial.answer is None else int(response == trial.answer)
    contacts = [f"{contact_s(trace):.4f}" for trace in traces] + ["", ""]
    return {"trial": trial.number, "practice": int(trial.practice),
            "stimuli": SEPARATOR.join(trial.stimuli), "value": _number(trial.value),
            "difference": _number(trial.difference), "answer": trial.answer or "",
            "response": response, "correct": correct, "rt_s": f"{rt_s:.4f}",
            "ended_utc": datetime.now(timezone.utc).isoformat(timespec="milliseconds"),
            "contact_1_s": contacts[0], "contact_2_s": contacts[1]}


@dataclass
class Session:
    """An open session folder (see the module docstring)."""

    folder: Path
    info: dict
    rows: list[dict]
    columns: tuple[str, ...] = RESULT_COLUMNS  # those of its results.csv
    #: a --resume found every trial answered: nothing ran, session.json is as it was
    complete_before: bool = False

    @property
    def seed(self) -> int:
        return int(self.info["seed"])

    @property
    def record(self) -> str:
        """What is kept per trial (one of ``session_schema.RECORDS``)."""
        return self.info.get("record", DEFAULT_RECORD)

    @property
    def results(self) -> Path:
        return self.folder / "results.csv"

    def trial_dir(self, number: int) -> Path:
        return self.folder / "trials" / f"{number:04d}"

    def append(self, row: dict) -> None:
        """Append ``row`` to the results table in one write and sync it to the disk."""
        buf = io.StringIO()
        csv.DictWriter(buf, self.columns, lineterminator="\n", extrasaction="ignore").writerow(row)
        fd = os.open(self.results, os.O_WRONLY | os.O_APPEND)
        try:
            os.write(fd, buf.getvalue().encode("utf-8"))
            os.fsync(fd)
        finally:
            os.close(fd)
        self.rows.append({k: str(row[k]) for k in self.columns})

    def write_interval(self, number: int, interval: int, scene_text: str, trace,
                       record: str) -> None:
        """Interval ``interval`` of trial ``number``: its scene (with the files it names,
        linked from ``stimuli/``) and trace, and with ``record = "all"`` their replay
        (what was sent to the device)."""
        from frictex.app.experiment.stimuli import place_files
        from frictex.rendering.input.trace_file import write_trace
        folder = self.trial_dir(number)
        folder.mkdir(parents=True, exist_ok=True)
        scene_path, trace_path = folder / f"{interval}.toml", folder / f"{interval}.csv"
        scene_path.write_text(scene_text, encoding="utf-8")
        place_files(tomllib.loads(scene_text), self.folder / "stimuli", folder)
        write_trace(trace_path, trace, comment=f"trial {number}, interval {interval}")
        if record == "all":
            from frictex.app.engine.replay import run_replay
            run_replay(scene_path, trace_path, folder / str(interval), progress=False)

    def sync_trial(self, number: int) -> None:
        folder = self.trial_dir(number)
        if folder.exists():
            _fsync_tree(folder)
            _fsync_dir(folder.parent)


def design(protocol) -> dict:
    """What ``frictex experiment analyse`` needs of a protocol (kept in session.json, so
    that a session folder is analysed without its scenes)."""
    from frictex.app.experiment.protocol import VARY_UNITS
    s = protocol.stimuli
    return {"vary": s.vary, "vary_unit": VARY_UNITS.get(s.vary), "reference": s.reference,
            "question": protocol.question,
            "guess": protocol.guess_rate,
            "target": protocol.target if protocol.guess_rate is not None else None,
            "analysis": asdict(protocol.analysis),
            "staircase": asdict(protocol.staircase) if protocol.staircase else None,
            "scale": list(protocol.scale) if protocol.scale else None}


def participant_id(text: str) -> str:
    """``--participant-id``: the participant's code, a plain name as a batch's job names
    are (``app.engine.batch.NAME``); InputError otherwise."""
    from frictex.app.engine.batch import NAME
    from frictex.device.safe_text import quoted
    if NAME.fullmatch(text) is None:
        raise InputError(f"--participant-id {quoted(text)}: expected a plain name (ASCII "
                         f"letters, digits, '.', '_' and '-', starting with a letter or a "
                         f"digit, at most 64), such as P07")
    return text


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def versions() -> dict:
    """What ran a session, as cheaply known: frictex's version, Python's, numpy's,
    scipy's and the platform (no commit: an installed frictex does not know its own)."""
    import numpy
    import scipy
    try:
        release = metadata.version("frictex")
    except metadata.PackageNotFoundError:
        release = "unknown (not installed)"
    return {"frictex": release, "python": platform.python_version(),
            "numpy": numpy.__version__, "scipy": scipy.__version__,
            "platform": platform.platform()}


def begin_part(session: Session, first_trial: int) -> None:
    """Record in session.json that a run of the session starts now at ``first_trial``
    (a part whose ``ended_utc`` stays null was killed)."""
    part = {"started_utc": _now(), "ended_utc": None, "first_trial": first_trial,
            "trials": 0, "ended": None, **versions()}
    session.info.setdefault("parts", []).append(part)
    _write_synced(session.folder / "session.json", json.dumps(session.info, indent=2) + "\n")


def end_part(session: Session, first_trial: int, complete: bool, why: str | None) -> None:
    """Record the end of the run begun by :func:`begin_part`: its trials, how it ended
    (``complete``, or stopped, ``why``: "SIGTERM", "Escape", "KeyboardInterrupt" for a
    Ctrl-C, an error's type; ``runner.stopped_by``) and, when ``complete``, the
    session's end."""
    part = session.info["parts"][-1]
    part.update(ended_utc=_now(), trials=len(session.rows) - (first_trial - 1),
                ended="complete" if complete else f"stopped ({why})")
    if complete:
        session.info["ended_utc"] = part["ended_utc"]
    _write_synced(session.folder / "session.json", json.dumps(session.info, indent=2) + "\n")


def create(folder: Path, protocol, seed: int, participant: str, pid: str | None = None,
           participant_seed: int | None = None, record: str = DEFAULT_RECORD) -> Session:
    """A new session in ``folder`` (made if needed; refused if it holds a session);
    ``pid``: the participant's code (:func:`participant_id`), or None;
    ``participant_seed``: the seed a simulated participant answers with, or None;
    ``record``: what is kept per trial (one of ``session_schema.RECORDS``)."""
    folder = Path(folder)
    if (folder / "results.csv").exists() or (folder / "session.json").exists():
        raise InputError(f"{folder} already holds a session; continue it with --resume, or "
                         f"give another --out")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "trials").mkdir(exist_ok=True)
    except OSError as exc:
        raise InputError(f"{folder}: cannot make the session folder ({exc.strerror})") from None
    info = {"format": FORMAT, "protocol": protocol.name, "method": protocol.method,
            "protocol_sha256": hashlib.sha256(protocol.text.encode("utf-8")).hexdigest(),
            "scene_sha256": scene_hashes(protocol),
            "seed": int(seed), "participant": participant,
            "participant_seed": participant_seed, "participant_id": pid, "record": record,
            **versions(), "started_utc": _now(), "ended_utc": None, "parts": [],
            "design": design(protocol)}
    _write_synced(folder / "protocol.toml", protocol.text)
    copy_scenes(folder, protocol)
    _write_synced(folder / "results.csv", ",".join(RESULT_COLUMNS) + "\n")
    _write_synced(folder / "session.json", json.dumps(info, indent=2) + "\n")
    return Session(folder, info, [])


#: largest session.json or results.csv read (bytes): a protocol's most trials (200,000: a
#: 2AFC of 100 levels, 1000 repetitions and 2 orders) take some 30 MB of either
MAX_SESSION_FILE_BYTES = 64 << 20


def session_file(folder: Path, name: str) -> Path:
    """``folder``/``name``, one of a session's own files: InputError where a symbolic
    link takes it out of the folder (a stranger's session folder makes analyse read
    nothing else, as a texture file's names are held to its folder)."""
    from frictex.textures.outside import leads_out
    how = leads_out(folder, name)
    if how is not None:
        raise InputError(f"{Path(folder) / name} {how}: a session's files are read from "
                         "its folder only")
    return Path(folder) / name


def read_info(folder: Path) -> dict:
    """``session.json`` of ``folder``, checked (``session_schema.check_info``: every key
    a reader uses, with the protocol's bounds; the design's ``analysis`` and ``staircase``
    with their defaults filled in); InputError when it is not a session folder. Read as a
    stranger's file: a regular UTF-8 file of at most :data:`MAX_SESSION_FILE_BYTES`, JSON
    of any nesting, and any key's value, a one-line error."""
    from frictex.textures.library import read_utf8
    path = Path(folder) / "session.json"
    if not path.exists() and not path.is_symlink():
        raise InputError(f"{folder}: not a session folder (no session.json)")
    session_file(folder, "session.json")
    try:
        info = json.loads(read_utf8(path, MAX_SESSION_FILE_BYTES))
    except InputError as exc:  # not a regular file, too large, not UTF-8 text
        raise InputError(f"{path}: cannot be read as a session ({exc})") from None
    except (ValueError, RecursionError) as exc:
        what = "nested too deep" if isinstance(exc, RecursionError) else exc
        raise InputError(f"{path}: cannot be read as a session (JSON {what})") from None
    if not isinstance(info, dict) or type(info.get("format")) is not int or (
            info["format"] != FORMAT):
        raise InputError(f"{path}: not a format {FORMAT} session file")
    return check_info(info, str(path))


def read_rows(folder: Path, repair: bool = False) -> list[dict]:
    """The rows of ``folder``'s results table (:func:`read_table`)."""
    return read_table(folder, repair)[1]


def torn_last_line(folder: Path) -> bool:
    """Whether ``folder``'s results.csv ends in a line without its line end (a write cut
    short), which :func:`read_table` does not count as a row."""
    from frictex.device.safe_files import read_bytes
    try:
        data = read_bytes(session_file(folder, "results.csv"), MAX_SESSION_FILE_BYTES)
    except (OSError, InputError):
        return False  # read_table says why it cannot be read
    return bool(data) and not data.endswith(b"\n")


def read_table(folder: Path, repair: bool = False) -> tuple[tuple[str, ...], list[dict]]:
    """The columns and rows of ``folder``'s results table (:data:`RESULT_COLUMNS`, or
    :data:`COLUMNS_BEFORE_CONTACT` for a table written before them). A last line without
    a line end (a write cut short) is not a row; ``repair`` also cuts it from the file."""
    from frictex.device.safe_files import read_bytes
    path = session_file(folder, "results.csv")
    try:
        data = read_bytes(path, MAX_SESSION_FILE_BYTES)  # a regular file, of bounded size
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    complete = data[:data.rfind(b"\n") + 1]
    if repair and len(complete) != len(data):
        with open(path, "r+b") as fh:
            fh.truncate(len(complete))
            os.fsync(fh.fileno())
    try:
        reader = csv.DictReader(io.StringIO(complete.decode("utf-8")))
        rows = list(reader)
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path}: not a results table ({exc})") from None
    columns = tuple(reader.fieldnames or ())
    if columns not in (RESULT_COLUMNS, COLUMNS_BEFORE_CONTACT):
        raise InputError(f"{path}: expected the columns {','.join(RESULT_COLUMNS)}")
    for i, row in enumerate(rows, start=1):
        if row.get("trial") != str(i) or None in row.values():
            raise InputError(f"{path}:{i + 1}: expected the row of trial {i} with "
                             f"{len(columns)} fields")
        rt = row["rt_s"]
        try:
            ok = math.isfinite(float(rt)) and float(rt) >= 0
        except ValueError:
            ok = False
        if not ok:
            raise InputError(f"{path}:{i + 1}: rt_s {rt!r}: expected a time in s")
    return columns, rows


def folder_of(text: str, option: str = "--out") -> Path:
    """The folder a command-line ``option`` names: InputError for an empty name (it
    would be the current folder) or one with a character ``str.isprintable`` refuses (a
    newline, a control character: every line naming the folder would break)."""
    from frictex.device.safe_text import quoted
    if not text.strip():
        raise InputError(f"{option} {quoted(text)}: expected a folder name (give . for the "
                         f"current folder)")
    if not text.isprintable():
        raise InputError(f"{option} {quoted(text)}: a folder name with a control character "
                         f"(a newline, a tab ...); give a plain name")
    return Path(text)


def _same_scenes(folder: Path, info: dict, protocol) -> None:
    """InputError naming the first of ``protocol``'s scene files that is not the one the
    session in ``folder`` started with (its sha256 in session.json; a session from
    before ``scene_sha256`` is not checked): a resumed session's later trials would
    play another stimulus than its first ones under the same name."""
    started = info.get("scene_sha256")
    if not isinstance(started, dict):
        return
    for key, path in scene_files(protocol).items():
        if started.get(key) != _sha256(path):
            raise InputError(f"{path}: not the scene {folder} was started with (it changed "
                             f"since, or is another file); restore it, or start a new "
                             f"session")


def _close_killed_part(info: dict, answered: int) -> None:
    """A last part without an end (its run was killed): its trials counted from the
    ``answered`` rows of results.csv and its end said to be unknown (written with the
    next part's start)."""
    parts = info.get("parts") or []
    if parts and isinstance(parts[-1], dict) and parts[-1].get("ended_utc") is None:
        first = parts[-1].get("first_trial", 1)
        parts[-1].update(trials=answered - (first - 1), ended="killed (no end recorded)")


def resume(folder: Path, protocol, participant: str | None, seed: int | None = None,
           pid: str | None = None, record: str | None = None) -> Session:
    """The session in ``folder``, ready to go on: the trial files of a trial without its
    row removed, a cut-short row dropped. InputError if ``protocol`` is not the one the
    session started with, or ``participant``, ``seed``, ``pid`` or ``record`` (if given)
    not its own (a session keeps what it records per trial, so that its trial files do
    not stop or start midway)."""
    folder = Path(folder)
    info = read_info(folder)
    if seed is not None and seed != info["seed"]:
        raise InputError(f"--seed {seed}: {folder} was started with seed {info['seed']}, and "
                         f"a resumed session keeps its trial order; leave --seed out")
    from frictex.textures.library import read_utf8
    try:
        started_with = read_utf8(folder / "protocol.toml", MAX_SESSION_FILE_BYTES)
    except InputError as exc:  # not a regular file, too large, not UTF-8 text
        raise InputError(f"{folder}: the session's protocol.toml cannot be read "
                         f"({exc})") from None
    if started_with != protocol.text:
        raise InputError(f"{protocol.source}: not the protocol {folder} started with (its copy "
                         f"is {folder / 'protocol.toml'})")
    _same_scenes(folder, info, protocol)
    if participant is not None and participant != info.get("participant"):
        raise InputError(f"--participant {participant}: {folder} was started with "
                         f"{info.get('participant')!r}")
    if pid is not None and pid != info.get("participant_id"):
        started = info.get("participant_id")
        raise InputError(f"--participant-id {pid}: {folder} was started "
                         + (f"with {started!r}" if started else "without a participant id"))
    if record is not None and "record" in info and record != info["record"]:
        raise InputError(f"--record {record}: {folder} was started with --record "
                         f"{info['record']}, and a resumed session keeps it; leave --record "
                         f"out")
    info.setdefault("record", record or DEFAULT_RECORD)
    columns, rows = read_table(folder, repair=True)
    _close_killed_part(info, len(rows))
    trials = folder / "trials"
    trials.mkdir(exist_ok=True)
    for leftover in trials.iterdir():
        if not (leftover.name.isdigit() and int(leftover.name) <= len(rows)):
            shutil.rmtree(leftover) if leftover.is_dir() else leftover.unlink()
    _fsync_dir(trials)
    return Session(folder, info, rows, columns)

"""A session with a person at the demo window, on the headless window: the real presenter
(``app.experiment.window_presenter``) and loop, the haptic thread in this process, a
hand injecting mouse strokes, clicks and key presses. Checks the results table, the
per-trial files (the traces replay with ``frictex replay`` to the commands the session
wrote) and that the screens' texts do not overlap. Every wait is bounded."""

import contextlib
import csv
import json
import os
import signal
import threading
import time

import numpy as np
import pytest

from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import run_session
from frictex.app.experiment.window_presenter import (SessionPaused, WindowPresenter, edit_rating,
                                                     how_to_answer, rating_problem,
                                                     response_keys, run_in_window,
                                                     stop_on_signals, typed_scale)
from frictex.app.live.haptic_setup import open_haptic
from frictex.app.commands.cli import main as cli_main
from frictex.app.experiment.session import contact_s
from frictex.rendering.input.trace_file import DOWN, read_trace
from frictex.rendering.visual.viewport import default_frame_size
from frictex.rendering.visual.windows import open_backend
from frictex.textures.loader import load_scene
from frictex.textures.library import resolve_scene

pytest.importorskip("moderngl", reason="moderngl (Python package) not installed")

PROTOCOL = """format = 1
name = "tiny-2afc"
method = "2afc"
repetitions = 1
practice = 1
break_every = 1

[stimuli]
scene = "grating-5mm"
vary = "period_mm"
reference = 5.0
levels = [6.6]

[presentation]
mode = "sequential"
exploration = "{exploration}"
exploration_s = {seconds}
{show_scene}"""
#: the hand moves on with Enter after its stroke: nothing waits on the machine's speed
FREE = {"exploration": "free", "seconds": 60, "show_scene": ""}
FIXED = {"exploration": "fixed", "seconds": 1.0, "show_scene": ""}
#: a window wider than the grating's 800 x 480 px: the scene fills its height
WIDE = (1000, 480)


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def wait_for(what, test, timeout_s=120.0):
    deadline = time.monotonic() + timeout_s
    while not (found := test()):
        assert time.monotonic() < deadline, f"waited {timeout_s} s for {what}"
        time.sleep(0.01)
    return found


def overlapping(boxes):
    """Pairs of text boxes (x, y, w, h) that overlap by more than a pixel."""
    out = []
    for i, (x, y, w, h) in enumerate(boxes):
        for (u, v, p, q) in boxes[i + 1:]:
            if min(x + w, u + p) - max(x, u) > 1 and min(y + h, v + q) - max(y, v) > 1:
                out.append(((x, y, w, h), (u, v, p, q)))
    return out


def test_keys_of_the_responses():
    assert response_keys(("1", "2")) == {"1": "1", "2": "2"}
    assert response_keys(("same", "different")) == {"s": "same", "d": "different"}
    scale = tuple(str(i) for i in range(1, 11))
    keys = response_keys(scale)
    assert keys["0"] == "10" and keys["7"] == "7" and len(keys) == 10
    zero_to_ten = response_keys(tuple(str(i) for i in range(0, 11)))
    assert zero_to_ten["0"] == "0" and "10" not in zero_to_ten.values()  # 10 by its button
    assert "(the others by their button)" in how_to_answer(
        tuple(str(i) for i in range(0, 12)), response_keys(tuple(str(i) for i in range(0, 12))))


class Hand:
    """The participant: answers each screen once it is drawn; records what it did."""

    def __init__(self, window, presenter, lose_at=None, escape_at=None, free=True):
        self.window, self.presenter = window, presenter
        self.free = free  # each interval ended with Enter after the stroke
        self.escape_at = escape_at  # the question (1-based) answered with Escape
        self.questions = 0
        self.lose_at = lose_at  # the interval (1-based) at which the output is lost
        self.intervals = 0
        self.answers = []  # the responses given, in order
        self.strokes = []  # (x_mm range) of each interval's stroke
        self.layouts = []  # text boxes of each message screen as drawn
        self.screens = []  # each message screen answered
        self.done = threading.Event()
        self.failure = None

    def click(self, box):
        x, y, w, h = box
        self.window.move(x + w / 2, y + h / 2)
        self.window.press()
        self.window.release()

    def run(self):
        """Act until done; a failure is kept (``failure``) and closes the window, which
        ends the session."""
        try:
            self.act()
        except BaseException as exc:  # raised by the test
            self.failure = exc
            self.window.close_window()

    def act(self):
        loop = wait_for("the loop", lambda: self.presenter.loop)
        seen = None
        while not self.done.is_set():
            screen = loop.screen
            drawn = loop.buttons
            if screen is seen or (screen.phase == "message" and not screen.buttons) or (
                    tuple((b.value, b.label) for b in drawn) != screen.buttons):
                time.sleep(0.01)
                continue
            seen = screen
            if screen.phase == "interval":
                self.intervals += 1
                if self.intervals == self.lose_at:  # the haptic side stops: a device lost
                    loop.haptic.error = OSError("the device stopped taking data (test)")
                else:
                    self.stroke(loop)
                    if self.free:
                        self.window.key("enter")
                continue
            frames = self.window.frames
            wait_for("a frame of the screen", lambda: self.window.frames > frames + 1)
            drawn = loop.buttons  # as drawn now (two screens may have the same buttons)
            self.layouts.append((screen.title, list(loop.compositor.text_boxes),
                                 loop.compositor.size))
            self.screens.append(screen)
            self.answer(screen, drawn)

    def answer(self, screen, drawn):
        """Answer a message screen (drawn, its buttons ``drawn``)."""
        values = [v for v, _ in screen.buttons]
        if values == ["1", "2"]:
            self.questions += 1
            if self.questions == self.escape_at:
                self.window.key("escape")
            elif not self.answers:  # the first answer by key, the others by button
                self.answers.append("1")
                self.window.key("1")
            else:
                self.answers.append("2")
                self.click(drawn[1].box)
        else:  # a message's first button: Start, Continue, Reconnect
            self.click(drawn[0].box)

    def move_until_it_ends(self, loop, screen, y: float) -> None:
        """Move the mouse back and forth across the scene at height ``y`` (px) until
        the loop shows another screen than ``screen`` (the interval ended)."""
        vp = loop.compositor.viewport
        deadline = time.monotonic() + 120.0
        for k in range(10**9):
            if loop.screen is not screen:
                return
            assert time.monotonic() < deadline, "the interval did not end"
            self.window.move(vp.x0 + (0.3 + 0.4 * (k % 2)) * vp.width_px, y)
            time.sleep(0.01)

    def stroke(self, loop):
        vp = loop.compositor.viewport
        xs = np.linspace(vp.x0 + 0.2 * vp.width_px, vp.x0 + 0.8 * vp.width_px, 15)
        y = vp.y0 + vp.height_px / 2
        self.window.move(xs[0], y)
        self.window.press()
        for x in xs[1:]:
            self.window.move(x, y)
            time.sleep(0.02)
        self.window.release()
        self.strokes.append(tuple(float(v) for v in vp.to_mm(xs[[0, -1]], [y, y])[0]))


class Frames:
    """The middle band (30-70 % of the height) of the scene's area in every frame drawn
    for an interval, and of every other frame the strip beside the status line (the
    right quarter of the scene's area above the message's cover) (``on_frame`` of the
    headless window)."""

    def __init__(self):
        self.loop = None
        self.bands = []
        self.strips = []
        self.titles = set()  # the window's titles while the intervals were shown

    def __call__(self, rgb):
        loop = self.loop
        drawn = getattr(loop, "_buttons_of", None)  # the screen this frame was drawn for
        if drawn is None:
            return
        self.titles.add(loop.backend.title)
        vp = loop.compositor.viewport
        if drawn.phase != "interval":
            top, right = int(loop.compositor.status_bottom), int(vp.x0 + vp.width_px)
            self.strips.append(rgb[int(vp.y0):top, right - int(vp.width_px) // 4:right].copy())
            return
        y0, y1 = int(vp.y0 + 0.3 * vp.height_px), int(vp.y0 + 0.7 * vp.height_px)
        self.bands.append(rgb[y0:y1, int(vp.x0):int(vp.x0 + vp.width_px)].copy())


def run_headless(tmp_path, lose_at=None, escape_at=None, resume=False, presentation=FREE,
                 frames=None, size=None, hand_class=Hand, protocol_text=PROTOCOL,
                 signals=False):
    """The tiny protocol's session in the headless window with a :class:`Hand`:
    (session, hand, session folder); ``frames`` (a :class:`Frames`) keeps the frames;
    ``size``: the window's (px), default the display's own; ``signals``: within the
    command's ``stop_on_signals``."""
    protocol_file = tmp_path / "tiny.toml"
    protocol_file.write_text(protocol_text.format(**presentation))
    protocol = load_protocol(protocol_file)
    scene = load_scene(resolve_scene("grating-5mm"))
    try:
        window = open_backend("headless", size or default_frame_size(scene.display),
                              on_frame=frames)
    except OSError as exc:
        pytest.skip(f"EGL unavailable: {exc}")
    out = tmp_path / "session"
    presenter = WindowPresenter()
    hand = hand_class(window, presenter, lose_at, escape_at, presentation["exploration"] == "free")

    if frames is not None:
        threading.Thread(target=lambda: setattr(frames, "loop", wait_for(
            "the loop", lambda: presenter.loop)), daemon=True).start()

    def start(sc, record):
        haptic, finish = open_haptic(sc, 10_000.0, 50, None, None, record)
        haptic.start()
        return haptic, finish

    thread = threading.Thread(target=hand.run, name="test-hand", daemon=True)
    thread.start()
    try:
        with stop_on_signals(presenter) if signals else contextlib.nullcontext():
            session = run_in_window(
                presenter, lambda: run_session(protocol, presenter, out, seed=7,
                                               participant="window", resume=resume),
                window, start, scene, out / "live", tmp_path / "shots")
    finally:
        hand.done.set()
        thread.join(timeout=30)
        if hand.failure is not None:
            raise hand.failure
    return session, hand, out


def test_a_session_in_the_headless_window(tmp_path):
    session, hand, out = run_headless(tmp_path)
    # the results: a practice trial and two main trials, answered as the hand did
    rows = read_csv(out / "results.csv")
    assert [r["practice"] for r in rows] == ["1", "0", "0"]
    assert [r["response"] for r in rows] == hand.answers == ["1", "2", "2"]
    assert len(session.rows) == 3
    assert all(0.0 < float(r["rt_s"]) < 120.0 for r in rows)
    # per trial and interval: the scene, the touches as sent, and their replay
    assert len(hand.strokes) == 6
    for k, (lo, hi) in enumerate(hand.strokes):
        trial, interval = k // 2 + 1, k % 2 + 1
        folder = out / "trials" / f"{trial:04d}"
        trace = read_trace(folder / f"{interval}.csv")
        assert trace.x_mm.min() == pytest.approx(lo, abs=1e-6)
        assert trace.x_mm.max() == pytest.approx(hi, abs=1e-6)
        assert 0.0 <= trace.t_s[0] and trace.t_s[-1] < 60.0
        assert (folder / str(interval) / "commands.csv").exists()
    # the trace replays with frictex replay to the commands the session wrote
    folder = out / "trials" / "0002"
    assert cli_main(["replay", str(folder / "1.toml"), str(folder / "1.csv"),
                     "--out", str(tmp_path / "again")]) == 0
    assert (tmp_path / "again" / "commands.csv").read_text() == \
        (folder / "1" / "commands.csv").read_text()
    # the live output: full-rate commands and the intervals' times on its clock
    events = read_csv(out / "live" / "events.csv")
    starts = [e for e in events if e["event"] == "interval-start"]
    assert len(starts) == 6
    assert len(read_csv(out / "live" / "commands.csv")) > 1000
    # the screens: instructions, a break before each main trial, the questions; legible
    titles = [t for t, _, _ in hand.layouts]
    assert titles[0] == "tiny-2afc" and titles.count("Break") == 2
    for title, boxes, (w, h) in hand.layouts:
        assert boxes, title
        assert not overlapping(boxes), title
        assert all(x >= 0 and y >= 0 and x + bw <= w + 1 and y + bh <= h + 1
                   for x, y, bw, bh in boxes), title


def test_a_fixed_exploration_lasts_its_time_on_the_haptic_clock(tmp_path):
    """Each interval ends by itself after ``exploration_s`` (one not touched in time, on a
    busy machine, is shown again); what the hand touched is recorded."""
    frames = Frames()
    # a frame wider than the display: the scene spans its height, under the status line
    session, hand, out = run_headless(tmp_path, presentation=FIXED, frames=frames,
                                      size=WIDE)
    assert [r["response"] for r in read_csv(out / "results.csv")] == hand.answers == ["1", "2", "2"]
    events = read_csv(out / "live" / "events.csv")
    times = {kind: [float(e["t_s"]) for e in events if e["event"] == kind]
             for kind in ("interval-start", "interval-end")}
    assert len(times["interval-start"]) == len(times["interval-end"]) >= 6
    assert all(end - start >= 1.0 for start, end in zip(times["interval-start"],
                                                          times["interval-end"]))
    for trial in (1, 2, 3):
        for interval in (1, 2):
            assert read_trace(out / "trials" / f"{trial:04d}" / f"{interval}.csv").t_s.size > 2
    # by default an interval shows a uniform field, not the grating: nothing to see
    assert len(frames.bands) >= 6
    for band in frames.bands:
        assert (band == band[0, 0]).all()
    assert frames.titles == {"frictex"}  # as opened: no stimulus's name (period_mm=6.6)
    assert frames.strips and all(strip.size for strip in frames.strips)
    for strip in frames.strips:  # beside the question's status line: no grating either
        assert (strip == strip[0, 0]).all()


def test_show_scene_shows_the_stimulus_while_it_is_explored(tmp_path):
    """``[presentation] show_scene = true``: the grating is drawn during the intervals
    (the band the default leaves uniform has its black and white stripes)."""
    frames = Frames()
    run_headless(tmp_path, presentation={**FREE, "show_scene": "show_scene = true\n"},
                 frames=frames, size=WIDE)
    assert frames.bands
    for band in frames.bands:
        assert band.max() - band.min() > 100
    assert any(strip.max() - strip.min() > 100 for strip in frames.strips)


def test_a_lost_device_pauses_and_reconnecting_repeats_the_trial(tmp_path):
    session, hand, out = run_headless(tmp_path, lose_at=3)  # trial 2's first interval
    rows = read_csv(out / "results.csv")
    assert [r["response"] for r in rows] == hand.answers == ["1", "2", "2"]
    assert hand.intervals == 7  # trial 2's first interval shown again after reconnecting
    titles = [t for t, _, _ in hand.layouts]
    assert titles.count("Output device lost") == 1
    events = read_csv(out / "live" / "events.csv")
    kinds = [e["event"] for e in events]
    assert "output-lost" in kinds and "paused" in kinds and "reconnect" in kinds
    # the new haptic side records beside the first; every trial's files are there
    assert (out / "live-2" / "commands.csv").exists()
    for trial in (1, 2, 3):
        for interval in (1, 2):
            assert read_trace(out / "trials" / f"{trial:04d}" / f"{interval}.csv").t_s.size > 2


def test_escape_ends_the_session_keeping_the_answers_and_resume_goes_on(tmp_path):
    with pytest.raises(SessionPaused, match="trial 2 .*Escape.*--resume"):
        run_headless(tmp_path, escape_at=2)
    out = tmp_path / "session"
    assert [r["response"] for r in read_csv(out / "results.csv")] == ["1"]
    assert not (out / "trials" / "0002").exists()  # the trial left is not recorded
    session, hand, _ = run_headless(tmp_path, resume=True)
    # the practice trial was answered before: the instructions no longer announce it
    assert not any("practice" in line for line in hand.screens[0].lines)
    rows = read_csv(out / "results.csv")
    assert [r["trial"] for r in rows] == ["1", "2", "3"]
    assert [r["response"] for r in rows] == ["1", *hand.answers]
    assert (out / "live-2" / "events.csv").exists()  # the resumed run's live output


class SignallingHand(Hand):
    """Sends its own process SIGTERM where :class:`Hand` would press Escape."""

    def answer(self, screen, drawn):
        if [v for v, _ in screen.buttons] == ["1", "2"] and self.questions + 1 == self.escape_at:
            self.questions += 1
            os.kill(os.getpid(), signal.SIGTERM)
            return
        super().answer(screen, drawn)


def test_sigterm_ends_the_window_session_recorded_as_sigterm(tmp_path):
    """A SIGTERM ends the session as Escape does, and session.json says SIGTERM stopped
    it, as the command's last line does; it said the window was closed."""
    from frictex.app.engine.driver import Terminated
    with pytest.raises(Terminated) as ended:
        run_headless(tmp_path, escape_at=2, hand_class=SignallingHand, signals=True)
    assert ended.value.code == 143
    assert ended.value.reason.startswith("terminated by SIGTERM at trial 2: ")
    info = json.loads((tmp_path / "session" / "session.json").read_text())
    assert info["parts"][-1]["ended"] == "stopped (SIGTERM)"
    assert [r["response"] for r in read_csv(tmp_path / "session" / "results.csv")] == ["1"]


class HoldingHand(Hand):
    """Presses once on a trial's first interval and holds the button, moving, until the
    question: across the switch to the second interval, as a participant may."""

    holding = False

    def stroke(self, loop):
        vp = loop.compositor.viewport
        y = vp.y0 + vp.height_px / 2
        shown = loop.screen
        if not self.holding:
            self.window.move(vp.x0 + 0.3 * vp.width_px, y)
            self.window.press()
            self.holding = True
        self.move_until_it_ends(loop, shown, y)
        if loop.screen.phase != "interval":  # the question (or shown again): lift
            self.window.release()
            self.holding = False


def test_a_button_held_across_intervals_touches_the_second(tmp_path):
    session, hand, out = run_headless(tmp_path, presentation=FIXED, hand_class=HoldingHand)
    assert "Not touched" not in [t for t, _, _ in hand.layouts]
    assert hand.intervals == 6
    for trial in (1, 2, 3):
        trace = read_trace(out / "trials" / f"{trial:04d}" / "2.csv")
        assert trace.event[0] == DOWN and contact_s(trace) >= 1.0


class LateHand(Hand):
    """Touches each interval only once it has been shown for 0.6 s (haptic clock)."""

    def stroke(self, loop):
        shown = loop.haptic.now()  # the interval started before its screen was set
        wait_for("0.6 s", lambda: loop.haptic.now() >= shown + 0.6)
        vp = loop.compositor.viewport
        y = vp.y0 + vp.height_px / 2
        screen = loop.screen
        self.window.move(vp.x0 + 0.3 * vp.width_px, y)
        self.window.press()
        self.move_until_it_ends(loop, screen, y)
        self.window.release()


def test_a_fixed_exploration_counts_from_the_first_touch(tmp_path):
    """Touched 0.6 s after it was shown, a 1 s interval still gives 1 s of contact (each
    trial's first interval: the second may be touched at once by the button still held
    from the first)."""
    session, hand, out = run_headless(tmp_path, presentation=FIXED, hand_class=LateHand)
    assert "Not touched" not in [t for t, _, _ in hand.layouts]
    for trial in (1, 2, 3):
        trace = read_trace(out / "trials" / f"{trial:04d}" / "1.csv")
        assert trace.t_s[0] >= 0.6 and contact_s(trace) >= 1.0 - 1e-6


def test_results_give_each_interval_its_contact_time_and_old_tables_still_read(tmp_path):
    from types import SimpleNamespace
    from frictex.app.experiment import session as S
    from frictex.rendering.input.trace_file import make_trace
    touched = make_trace(np.array([0.6, 1.0, 1.6, 2.0, 2.5]), np.zeros(5, dtype=np.int64),
                         np.zeros(5), np.zeros(5), np.ones(5), np.array([0, 1, 2, 0, 2], dtype=np.int8))
    trial = SimpleNamespace(number=1, practice=False, stimuli=("a", "b"), value=1.0,
                            difference=0.1, answer="1")
    row = S.result_row(trial, "1", 0.5, (touched,))
    assert (row["contact_1_s"], row["contact_2_s"]) == ("1.5000", "")
    old = tmp_path / "old"
    old.mkdir()
    (old / "results.csv").write_text(",".join(S.COLUMNS_BEFORE_CONTACT) + "\n")
    session = S.Session(old, {}, [], S.read_table(old)[0])
    session.append(row)  # a resumed old table goes on in its own columns
    assert S.read_rows(old)[0]["response"] == "1" and "contact_1_s" not in S.read_rows(old)[0]


MAGNITUDE = """format = 1
name = "wide-scale"
method = "magnitude"
repetitions = 1

[stimuli]
scene = "grating-5mm"
vary = "period_mm"
reference = 5.0
levels = [6.6]

[scale]
min = 0
max = 100

[presentation]
exploration = "{exploration}"
exploration_s = {seconds}
{show_scene}"""


def test_which_scales_are_typed_and_how_a_rating_is_edited():
    assert typed_scale(("1", "2")) is None and typed_scale(("same", "different")) is None
    assert typed_scale(tuple(str(i) for i in range(1, 11))) is None  # a key per value
    assert typed_scale(tuple(str(i) for i in range(0, 101))) == (0, 100)
    assert typed_scale(tuple(str(i) for i in range(-5, 5))) == (-5, 4)
    text = ""
    for key in ("5", "6", "7", "7", "backspace", "left", "x", "9"):
        text = edit_rating(text, key, (0, 100))
    assert text == "59"  # three digits at most
    # a minus on a scale from 0 was dropped, so '-5' was taken as 5; it is kept and refused
    assert edit_rating("5", "minus", (0, 100)) == "-5"
    assert rating_problem("-5", (0, 100)) == ("-5 is not on the scale: type a number from "
                                               "0 to 100.")
    assert edit_rating("12", "minus", (-1000, 1000)) == "-12"
    assert edit_rating("-12", "minus", (-1000, 1000)) == "12"
    assert rating_problem("777", (0, 100)) == ("777 is not on the scale: type a number from "
                                                "0 to 100.")
    assert rating_problem("", (0, 100)).startswith("Type a number")
    assert rating_problem("-", (-5, 4)).startswith("Type a number")
    assert rating_problem("100", (0, 100)) is None and rating_problem("-5", (-5, 4)) is None


class TypingHand(Hand):
    """Types each rating: the first as two digits confirmed with the Confirm button once
    the screen shows it, the second in one burst of keys (a value off the scale, Enter,
    corrected, Enter) that the presenter must take whole."""

    typed = ()

    def answer(self, screen, drawn):
        if screen.buttons[0][0] != "confirm":
            return super().answer(screen, drawn)
        if screen.progress in self.typed:  # the same question, updated as typed
            return
        self.typed += (screen.progress,)
        loop = self.presenter.loop
        if len(self.typed) == 1:
            self.window.key("5")
            self.window.key("6")
            shown = wait_for("the rating on the screen", lambda: loop.screen if (
                "Your rating: 56" in loop.screen.lines and loop._buttons_of is loop.screen
                and loop.buttons) else None)
            self.layouts.append(("typed", list(loop.compositor.text_boxes), loop.compositor.size))
            self.answers.append("56")
            self.click(next(b for b in loop.buttons if b.value == "confirm").box)
            assert shown.buttons[0] == ("confirm", "Confirm (Enter)")
        else:
            for key in ("7", "7", "7", "7", "enter", "backspace", "backspace", "backspace",
                        "1", "0", "0", "enter"):
                self.window.key(key)
            self.answers.append("100")


def test_a_wide_scale_is_answered_by_typing_the_rating(tmp_path):
    """0-100 (101 values: their buttons did not fit the window, and the keys 0-9 gave 5 for
    "5" then "6"): the rating is typed, shown as typed and confirmed; every value is
    reachable, and one off the scale is not taken."""
    session, hand, out = run_headless(tmp_path, hand_class=TypingHand, protocol_text=MAGNITUDE)
    rows = read_csv(out / "results.csv")
    assert [r["response"] for r in rows] == hand.answers == ["56", "100"]
    instructions = hand.layouts[0]
    assert instructions[0] == "wide-scale"
    for title, boxes, (w, h) in hand.layouts:
        assert not overlapping(boxes), title
        assert all(y + bh <= h + 1 for _, y, _, bh in boxes), title

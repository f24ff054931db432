"""The headless demo's synthetic hand makes its stroke a piece at a time: a long
--duration (1e9 s) built the whole stroke before its first position (1e6 s: 21 s and
188 MB; 1e9 s: minutes of CPU, gigabytes, SIGTERM unanswered meanwhile)."""

import numpy as np

import frictex.app.live.synthetic as synthetic
from frictex.app.live.synthetic import EVENTS_HZ, SPEED_MM_S, SyntheticStroke

AREA_MM = (108.0, 64.8)


class Window:
    """Takes the hand's events: pointer positions (mm, as to_px is the identity) and keys."""

    def __init__(self):
        self.moves, self.keys, self.pressed = [], [], False

    def move(self, x, y):
        self.moves.append((x, y))

    def press(self):
        self.pressed = True

    def release(self):
        self.pressed = False

    def key(self, name):
        self.keys.append(name)


def test_a_long_stroke_is_made_a_piece_at_a_time(monkeypatch):
    made = []
    make = synthetic.make_motion

    def recorded(kind, **kwargs):
        made.append(kwargs["duration_s"])
        return make(kind, **kwargs)

    monkeypatch.setattr(synthetic, "make_motion", recorded)
    hand = SyntheticStroke(Window(), lambda x, y: (x, y), AREA_MM, duration_s=1e9)
    t = np.arange(0.0, 200.0, 1.0 / EVENTS_HZ)
    path = np.array([hand._position(float(s)) for s in t])
    assert max(made) <= 60.0 and len(made) == 4  # 0-60, 60-120, 120-180, 180-240 s
    steps_mm = np.hypot(*np.diff(path, axis=0).T)
    # each piece goes on from where the last ended: no jump at 60, 120 or 180 s, every
    # step within the stroke's fastest peak speed (1.8 x its typical one)
    assert steps_mm.max() <= 1.8 * SPEED_MM_S / EVENTS_HZ
    assert ((path >= 0.0) & (path <= AREA_MM)).all()


def test_the_hand_strokes_to_its_end_across_pieces_then_quits():
    window, now = Window(), [0.0]
    hand = SyntheticStroke(window, lambda x, y: (x, y), AREA_MM, duration_s=130.0,
                           clock=lambda: now[0],
                           sleep=lambda s: now.__setitem__(0, now[0] + s))
    hand.run()
    assert len(window.moves) == 130 * EVENTS_HZ + 1 and hand.stroked_s == 130.0
    assert hand.piece == 2 and window.keys == ["q"] and not window.pressed


def test_on_a_display_too_thin_for_a_human_stroke_the_hand_goes_back_and_forth_along_it():
    """A beam's display (350 x 6 mm): the human stroke keeps 8 mm from the edges, so the
    headless demo of every bundled beam scene refused to start ('area 350 x 6 mm: a human
    motion keeps 8 mm from the area's edges')."""
    for area, along in (((350.0, 6.0), 0), ((6.0, 120.0), 1), ((10.0, 3.0), 0)):
        hand = SyntheticStroke(Window(), lambda x, y: (x, y), area, duration_s=1e9)
        t = np.arange(0.0, 30.0, 1.0 / EVENTS_HZ)
        path = np.array([hand._position(float(s)) for s in t])
        assert ((path >= 0.0) & (path <= area)).all()
        np.testing.assert_allclose(path[:, 1 - along], area[1 - along] / 2)  # its middle
        margin = min(8.0, area[along] / 4)  # from its ends
        assert np.isclose(np.ptp(path[:, along]), area[along] - 2 * margin)
        steps_mm = np.hypot(*np.diff(path, axis=0).T)
        assert steps_mm.max() <= SPEED_MM_S / EVENTS_HZ * (1 + 1e-9)

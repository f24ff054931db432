"""The ``--faults`` grammar and the timed fault events a port plays."""

import pytest
import serial
from hypothesis import given, settings, strategies as st

from frictex.device.link.faults import (TRIP_S, Event, FaultPlan, Faults, FaultSpecError, FaultyPort,
                                Plug, Schedule, parse_faults)


def test_the_documented_example_parses_to_its_plan():
    plan = parse_faults("stall=0.2@1.5,corrupt=0.01,drop=0.005,trip@3,unplug=2.0@4,seed=7")
    assert plan == FaultPlan(Faults(flip=0.01, drop=0.005),
                             (Event("stall", 1.5, 0.2), Event("trip", 3.0, TRIP_S),
                              Event("unplug", 4.0, 2.0)), 7)


PROB = st.floats(0.0, 0.999, allow_nan=False)
TIME = st.floats(0.0, 1e4, allow_nan=False)
DURATION = st.floats(1e-3, 3600.0, allow_nan=False)
ITEMS = st.one_of(
    st.tuples(st.sampled_from(["corrupt", "drop", "garbage"]), PROB).map(
        lambda t: (f"{t[0]}={t[1]!r}", ("rate", t[0], t[1]))),
    st.tuples(st.sampled_from(["stall", "unplug"]), DURATION, TIME).map(
        lambda t: (f"{t[0]}={t[1]!r}@{t[2]!r}", ("event", Event(t[0], t[2], t[1])))),
    TIME.map(lambda at: (f"trip@{at!r}", ("event", Event("trip", at, TRIP_S)))),
    st.integers(0, 2**31).map(lambda n: (f"seed={n}", ("seed", n))))


@settings(derandomize=True, max_examples=150, deadline=None)
@given(st.lists(ITEMS, min_size=1, max_size=8), st.sampled_from([",", ", "]))
def test_any_spec_of_the_grammar_reads_back_what_was_written(items, sep):
    plan = parse_faults(sep.join(text for text, _ in items))
    rates, events, seed = {}, [], 0
    for _, (kind, *value) in items:  # later items of a rate or the seed win
        if kind == "rate":
            rates[{"corrupt": "flip"}.get(value[0], value[0])] = value[1]
        elif kind == "event":
            events.append(value[0])
        else:
            seed = value[0]
    assert plan.faults == Faults(**rates)
    assert sorted(plan.events, key=lambda e: (e.at_s, e.kind, e.duration_s)) == sorted(
        events, key=lambda e: (e.at_s, e.kind, e.duration_s))
    assert [e.at_s for e in plan.events] == sorted(e.at_s for e in plan.events)
    assert plan.seed == seed


@pytest.mark.parametrize("spec, message", [
    ("", "empty fault spec"),
    ("jitter=0.1", "fault 'jitter=0.1': unknown name 'jitter'; expected one of corrupt"),
    ("corrupt", "fault 'corrupt': expected corrupt=PROBABILITY"),
    ("corrupt=0.1@2", "expected corrupt=PROBABILITY"),
    ("corrupt=1", "probability 1 is outside [0, 1)"),
    ("drop=-0.1", "probability -0.1 is outside [0, 1)"),
    ("garbage=nan", "probability nan is outside [0, 1)"),
    ("stall=0.2", "fault 'stall=0.2': expected stall=SECONDS@SECONDS"),
    ("stall=abc@1", "duration 'abc' is not a number"),
    ("stall=0@1", "duration 0 is outside (0, 3600]"),
    ("unplug=2@-1", "start time -1 is outside [0, inf]"),
    ("unplug=2@inf", "start time inf is outside [0, inf]"),
    ("trip=0.1@3", "fault 'trip=0.1@3': expected trip@SECONDS"),
    ("trip@", "start time '' is not a number"),
    ("seed=x", "'x' is not an integer; expected seed=INTEGER"),
    ("seed=-3", "seed must be >= 0"),
    ("corrupt=0.1,,drop=0.1", "fault '': unknown name ''"),
])
def test_a_bad_spec_is_one_clear_line_naming_the_item(spec, message):
    with pytest.raises(FaultSpecError, match="^[^\n]*$") as info:
        parse_faults(spec)
    assert message in str(info.value)
    assert isinstance(info.value, ValueError)


class FakeClock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


class Wire:
    """A port that records what was written."""

    def __init__(self):
        self.written = b""

    def write(self, data):
        self.written += data

    def read(self, size=1):
        return b""

    in_waiting = 0

    def close(self):
        pass


def test_timed_events_trip_and_unplug_the_port_then_end():
    clock = FakeClock()
    schedule = Schedule((Event("trip", 1.0, TRIP_S), Event("unplug", 2.0, 0.5)), clock=clock)
    wire = Wire()
    plug = Plug(lambda: wire, schedule=schedule)
    port = plug()
    port.write(b"a")
    clock.t += 1.0 + TRIP_S / 2   # inside the trip: writes vanish, reads still work
    port.write(b"b")
    assert port.read() == b""
    clock.t += TRIP_S             # trip over
    port.write(b"c")
    assert wire.written == b"ac"
    clock.t = 100.0 + 2.2         # unplugged: the port and reopening both fail
    with pytest.raises(serial.SerialException, match="unplugged"):
        port.write(b"d")
    with pytest.raises(serial.SerialException, match="unplugged"):
        plug()
    clock.t = 100.0 + 2.6
    plug().write(b"e")
    assert wire.written == b"ace"


def test_a_stall_event_holds_the_calling_thread_until_it_ends(monkeypatch):
    slept = []
    clock = FakeClock()

    def sleep(s):
        slept.append(s)
        clock.t += s
    monkeypatch.setattr("frictex.device.link.faults.time.sleep", sleep)
    schedule = Schedule((Event("stall", 0.0, 0.25),), clock=clock)
    clock.t += 0.05
    port = FaultyPort(Wire(), Faults(), schedule=schedule)
    port.write(b"x")   # 0.05 s into the stall: waits the remaining 0.20 s
    port.write(b"y")   # over: no second wait
    assert slept == [pytest.approx(0.20)]


def test_events_past_the_links_end_are_said_never_to_have_come(tmp_path, capsys):
    """trip@30 on a 2 s replay was accepted and never played, and nothing said so: a
    user testing the device's watchdog took the run for one that survived a trip."""
    import json
    from frictex.app.commands.cli import main
    out = tmp_path / "out"
    main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out), "--device", "sim",
          "--faults", "stall=0.05@0.5,trip@30,unplug=1@40", "--max-unplayed", "1", "--quiet"])
    device = json.loads((out / "summary.json").read_text())["device"]
    assert device["fault_events_not_reached"] == ["trip@30", "unplug=1@40"]
    assert ("frictex: warning: --faults trip@30, unplug=1@40: never came, the link ended "
            "before (event times count from when the link opened)") in capsys.readouterr().err


def test_a_link_without_faults_has_none_not_reached(tmp_path):
    import json
    from frictex.app.commands.cli import main
    out = tmp_path / "out"
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out), "--device",
                 "sim", "--max-unplayed", "1", "--quiet"]) == 0
    assert json.loads((out / "summary.json").read_text())["device"][
        "fault_events_not_reached"] == []

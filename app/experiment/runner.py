"""Running a session: the scheduler's trials shown by a presenter, recorded as they end.

A presenter (``presenter.Presenter``) shows a trial's stimuli and returns the
participant's answer. The runner owns everything else: which trial comes next
(``scheduler``), the scenes (``stimuli.StimulusBank``), the session folder
(``session``). Presenters register by
name in :data:`PARTICIPANTS` (``--participant NAME:OPTIONS``): ``simulated`` (the
observer model, headless); the demo window registers its own.

    session = run_session(protocol, presenter, "out/p01")
"""

from __future__ import annotations

import secrets
import signal
from dataclasses import replace
from pathlib import Path
from typing import Callable

from frictex.app.engine.driver import in_front, tell_run_saw
from frictex.app.experiment import session as S
from frictex.app.experiment.presenter import Presenter, Shown
from frictex.app.experiment.protocol import Protocol as ExperimentProtocol
from frictex.app.experiment.protocol import Stimulus
from frictex.app.experiment.scheduler import Scheduler, Trial
from frictex.app.experiment.session_schema import RECORDS
from frictex.app.experiment.stimuli import StimulusBank, name_of
from frictex.device.errors import InputError
from frictex.device.registry import Registry


#: ``--participant NAME:OPTIONS`` -> a factory taking OPTIONS and giving a Presenter
PARTICIPANTS: Registry[Callable[[str], Presenter]] = Registry("participant",
                                                              "frictex.participants")


def _simulated(options: str) -> Presenter:
    from frictex.app.experiment.observer import parse_spec
    return parse_spec(options)


PARTICIPANTS.register("simulated", _simulated)
#: the simulated participant's seed in a session.json that does not record one (written
#: before participant_seed was): the spec's default then
LEGACY_PARTICIPANT_SEED = 0


def make_presenter(spec: str) -> Presenter:
    """``simulated:weber=0.11,lapse=0.02`` -> the registered participant's presenter."""
    name, _, options = spec.partition(":")
    return PARTICIPANTS.get(name)(options)


class _Stage:
    """The scenes of a protocol's trials (``Shown`` per interval)."""

    def __init__(self, protocol: ExperimentProtocol, bank: StimulusBank):
        self.protocol = protocol
        self.bank = bank
        s = protocol.stimuli
        self.listed = {st.name: st for st in s.listed}

    def stimulus(self, name: str, trial: Trial) -> Stimulus:
        if name in self.listed:
            return self.listed[name]
        s = self.protocol.stimuli
        value = s.reference if name == name_of(s.vary, s.reference, None) else trial.value
        return Stimulus(name, s.scene, value, None)

    def shown(self, trial: Trial) -> list[Shown]:
        p = self.protocol
        s, pres = p.stimuli, p.presentation
        stimuli = [self.stimulus(name, trial) for name in trial.stimuli]
        free = pres.exploration == "free"
        if pres.mode == "side-by-side" and len(stimuli) == 2:
            scene, text = self.bank.pair(*stimuli, s.vary, s.layer)
            w, h = scene.display.width_mm, scene.display.height_mm
            name = f"{stimuli[0].name}+{stimuli[1].name}"
            return [Shown(name, scene, text, (0.0, 0.0, w / 2, h), pres.exploration_s, free),
                    Shown(name, scene, text, (w / 2, 0.0, w / 2, h), pres.exploration_s, free)]
        out = []
        for st in stimuli:
            scene, text = self.bank.get(st, s.vary, s.layer)
            area = (0.0, 0.0, scene.display.width_mm, scene.display.height_mm)
            out.append(Shown(st.name, scene, text, area, pres.exploration_s, free))
        return out


def run_session(protocol: ExperimentProtocol, presenter: Presenter, out_dir: str | Path, *,
                seed: int | None = None, participant: str = "", participant_id: str | None = None,
                resume: bool = False,
                record: str | None = None, progress: Callable[[Trial, dict], None] | None = None,
                between_trials: Callable[[], None] | None = None) -> S.Session:
    """Run (or with ``resume`` go on with) the session of ``protocol`` in ``out_dir``.

    ``seed``: the trial order's seed (default: the protocol's, else drawn now; recorded
    in session.json; with ``resume``, refused unless it is the session's; out of range,
    refused before anything is written). A presenter with a ``settle_seed(session_seed,
    recorded)`` method (the simulated participant) is given the session's seed and the
    participant seed the session recorded (resume); the seed it returns is recorded.
    ``participant``: the participant spec, recorded; ``participant_id``: the person's
    code (``session.participant_id``), recorded (with ``resume``, refused unless the
    session's). ``record``: ``all`` (per trial: scene, trace and their replay), ``traces`` (scene and trace) or
    ``results`` (the results table only); recorded in session.json; None: ``all`` for a
    new session, the session's own with ``resume`` (a different one is refused). ``progress(trial, row)`` is called after each
    trial is recorded; ``between_trials()`` before each trial after the first of this run
    (where a command stops the session: the trials before are recorded, none is begun).
    A presenter with a ``starts_at(first_trial)`` method (the window) is told the trial
    this run starts at before ``begin``; with ``resume`` the protocol keeps the name the
    session started with (DIR/protocol.toml would name it "protocol").
    Returns the session (its ``rows``: every trial answered).
    With ``resume`` on a complete session, nothing runs and session.json is left as it
    is (the session's ``complete_before`` says so).
    """
    if record is not None and record not in RECORDS:
        raise InputError(f"record {record!r}: expected one of {', '.join(RECORDS)}")
    out_dir = Path(out_dir)
    settle = getattr(presenter, "settle_seed", None)
    if resume:
        session = S.resume(out_dir, protocol, participant or None, seed, participant_id,
                           record)
        if isinstance(session.info.get("protocol"), str):  # DIR/protocol.toml without a name
            protocol = replace(protocol, name=session.info["protocol"])  # would be "protocol"
        scheduler = Scheduler(protocol, session.seed)
        if settle is not None:  # a session.json from before participant_seed: 0, as then
            settle(session.seed, session.info.get("participant_seed", LEGACY_PARTICIPANT_SEED))
    else:
        if seed is None:
            seed = protocol.seed if protocol.seed is not None else secrets.randbits(63)
        scheduler = Scheduler(protocol, seed)  # a bad seed refused before anything is written
        session = S.create(out_dir, protocol, seed, participant, participant_id,
                           None if settle is None else settle(seed),
                           record or S.DEFAULT_RECORD)
    state = scheduler.replay((row["stimuli"].split(S.SEPARATOR), row["response"])
                             for row in session.rows)
    if resume and scheduler.finished(state):  # no run, so no empty part in session.json
        session.complete_before = True
        return session
    stage = _Stage(protocol, StimulusBank(out_dir / "stimuli"))
    first = len(session.rows) + 1
    S.begin_part(session, first)
    # the command's handler raises a KeyboardInterrupt for SIGTERM too (StartupSignals):
    # the signal is known here, not from the exception
    with in_front(_SignalsSeen()) as seen:
        try:
            starts_at = getattr(presenter, "starts_at", None)
            if starts_at is not None:
                starts_at(first)
            presenter.begin(protocol)
            _run_trials(scheduler, state, stage, presenter, session, session.record,
                        progress, between_trials)
        except BaseException as exc:
            S.end_part(session, first, False, stopped_by(exc, seen.signum))
            raise
    S.end_part(session, first, True, None)
    return session


def stopped_by(exc: BaseException, signum: int | None) -> str:
    """Why a run ended by ``exc`` stopped, as session.json's part says ("stopped (WHY)"):
    the window's reason (``why``: "Escape"), the signal's name where ``exc`` carries a
    SIGTERM or SIGHUP (a replay's ``Terminated``) or is the KeyboardInterrupt the
    command raises for the run's first signal ``signum`` (None: none came), as the
    command's last line names it; else the exception's type (Ctrl-C: KeyboardInterrupt)."""
    why = getattr(exc, "why", None)
    if why:
        return why
    carried = getattr(exc, "signum", None)
    if carried is None and isinstance(exc, KeyboardInterrupt):
        carried = signum
    if carried is not None and carried != signal.SIGINT:
        return signal.Signals(carried).name
    return type(exc).__name__


class _SignalsSeen:
    """The first SIGINT, SIGTERM or SIGHUP a run got (``signum``; None while none), each
    passed on to the handler it replaced, as is a replay's word of one (``run_saw``,
    ``driver.tell_run_saw``): that handler decides what the signal does."""

    def __init__(self):
        self.signum: int | None = None
        self.previous: dict[int, object] = {}

    def __call__(self, signum, frame) -> None:
        self._saw(signum)
        self.previous[signum](signum, frame)

    def run_saw(self, signum: int, ended: bool) -> None:
        self._saw(signum)
        tell_run_saw(self.previous[signum], signum, ended)

    def _saw(self, signum: int) -> None:
        if self.signum is None:
            self.signum = signum


def _run_trials(scheduler: Scheduler, state, stage: _Stage, presenter: Presenter,
                session: S.Session, record: str,
                progress: Callable[[Trial, dict], None] | None,
                between_trials: Callable[[], None] | None) -> None:
    """The trials from ``state`` to the session's end, each recorded as it is answered."""
    first = True
    while (trial := scheduler.next_trial(state)) is not None:
        if not first and between_trials is not None:
            between_trials()
        first = False
        if trial.break_before:
            presenter.rest(trial)
        shown = stage.shown(trial)
        result = presenter.present(trial, shown)
        if result.response not in trial.responses:
            raise InputError(f"trial {trial.number}: the presenter answered "
                             f"{result.response!r}; expected one of {', '.join(trial.responses)}")
        if record != "results":
            for interval, (item, trace) in enumerate(zip(shown, result.traces), start=1):
                session.write_interval(trial.number, interval, item.text, trace, record)
            session.sync_trial(trial.number)
        row = S.result_row(trial, result.response, result.rt_s, result.traces)
        session.append(row)
        state = scheduler.answer(state, trial, result.response)
        if progress is not None:
            progress(trial, row)

"""TUIO 1.1 cursors (``/tuio/2Dcur``) over UDP/OSC to touch samples.

OSC 1.0 wire grammar (all fields big-endian, everything padded to 4 bytes)::

    packet  := message | bundle
    bundle  := "#bundle\\0" timetag(8) { size(int32) packet(size bytes) }
    message := address(string) typetags(string ",...") { argument }
    string  := bytes "\\0" padding-to-4
    argument: i int32 | f float32 | s S string | b int32-size bytes padding | h int64
              | d float64 | t timetag(uint64) | c char(int32) | r rgba(4) | m midi(4)
              | T true | F false | N nil | I infinitum (no bytes)

TUIO 1.1 2Dcur profile (Kaltenbrunner et al., "TUIO: A protocol for table-top tangible user
interfaces", 2005; TUIO 1.1 specification): one bundle per frame, holding

    /tuio/2Dcur source s               (optional: which tracker; scopes the session ids)
    /tuio/2Dcur alive i...             (session ids touching now; those missing have lifted)
    /tuio/2Dcur set s x y X Y m        (session id, position 0..1 from the top-left, velocity, accel.)
    /tuio/2Dcur fseq f                 (frame number; ends the frame)

A frame whose fseq is lower than the last one from its source, by at most 100, arrived
late (UDP reorders) and is dropped, as the TUIO reference client does; fseq <= 0 is always
accepted. Positions are normalised; :class:`TuioListener` maps them to the display's mm.
TUIO 1.1 carries no usable time, so samples are stamped with their arrival time: the
kernel's receive time of the datagram (``SO_TIMESTAMPNS``) where the system gives it,
so that a receiving thread held up (a busy machine, the GIL) does not delay the stamp.

Who may send. A datagram moves a finger on the plate, so :class:`TuioListener` listens
on loopback (127.0.0.1) unless given another address, and takes datagrams from one
sender only: the address (and port, if given) it is told to accept, or else the first
sender of a well-formed TUIO frame (a bundle that parses and holds ``/tuio/2Dcur alive``
and ``fseq``: :func:`is_tuio_frame`), its address and port, so that another process on
the same host cannot join in. Until a sender is accepted, datagrams that are not such a
frame claim nothing: stray traffic cannot lock the tablet out. Deciding costs little
whatever a stranger sends: a datagram over :data:`MAX_CLAIM_BYTES`, or not starting as a
2Dcur bundle, is refused from its first bytes, and each sender (address and port) has one
datagram parsed at most every :data:`CLAIM_INTERVAL_S`, so that one process's junk does
not delay another's claim. Datagrams from anyone
else, and those unclaiming ones, are dropped and counted (``refused``). Listening beyond
loopback with no sender named, :func:`exposure_warning` gives the line a command prints;
a sender named beyond loopback for a listener on loopback, which can never hear it,
:func:`unreachable_sender` gives the error.

Malformed datagrams. One whose OSC cannot be read, or whose ``source``, ``alive`` or
``fseq`` cannot, is dropped whole; a ``set`` that cannot be played (a position not
finite or off the screen, arguments of the wrong type) is skipped alone, and its frame
played: the cursor, still in ``alive``, keeps its last good position.

Silence. UDP has no goodbye: a tracker that crashes, or a sender that exits without an
empty ``alive``, leaves its cursors touching. TUIO 1.1 senders repeat ``alive`` and
``fseq`` in every frame (30 to 60 Hz from a camera or touch panel), and the reference
TuioServer, when nothing moves, still resends its state every ``update_interval`` s
(1 s by default, whole seconds). So a source silent for :data:`SILENCE_S` (1.5 s: the
reference server's idle resend with half a second to spare, 45 to 90 frames of a
sender that keeps its frame rate) has gone: its cursors are lifted (UP at the time the
silence was seen) and its frame numbers forgotten, and the listener says so once on
stderr (``TUIO: no message from HOST:PORT for 1.5 s: lifted N fingers``, or ``no valid
frame from HOST:PORT for 1.5 s (N datagrams, M malformed)`` when datagrams came but
none played a frame). Silence is
judged by the clock, but a sender with a TUIO frame (:func:`may_be_tuio_frame`) still
queued is not silent, however late the polling thread is: a backlog of frames never lifts
a finger only to press it again; one of other datagrams does not keep it pressed. One
sender is served at a time (:class:`SenderGate`): the first, and after it has been silent
for :data:`SILENCE_S`, the first sender of a TUIO frame after that (a restarted tracker on
a new port, another tablet); while it speaks, every other sender is refused, however much
it sends. Within the served sender, each ``source`` name falls silent on its own.
"""

from __future__ import annotations

import ipaddress
import math
import queue
import socket
import struct
import sys
import threading
import time
from typing import Callable, Container

from frictex.rendering.input.evdev_decode import AxisMap, RawSample, ScreenMap, TouchSample
from frictex.device.errors import InputError
from frictex.device.safe_text import quoted
from frictex.rendering.input.trace_file import DEFAULT_FORCE_N, DOWN, MOVE, UP, TraceError

TUIO_PORT = 3333
TUIO_HOST = "127.0.0.1"  # listen on loopback unless told otherwise
_MAX_DEPTH = 8
#: accepted late-frame jump: an fseq this much below the last one is a tracker restart
_FSEQ_RESTART = 100
#: most cursors touching at once (two hands' fingers, twice over) and most TUIO sources
MAX_CURSORS = 20
MAX_SOURCES = 8
#: a 2Dcur position is normalised to the screen (0 to 1); one this far beyond it on either
#: side is a finger just off its edge, further is no touch of this screen
POSITION_RANGE = (-0.5, 1.5)
#: a TUIO source silent this long (s) has gone: its cursors are lifted (module docstring)
SILENCE_S = 1.5
#: most ids of a 2Dcur ``alive`` read (MAX_CURSORS four times over): those after them,
#: and any message's arguments after its first ``MAX_ALIVE_IDS + 1``, are refused unread
#: (counted ``unread`` in a 2Dcur message), so that an 8,000-id list costs no more to
#: decode than an 80-id one
MAX_ALIVE_IDS = 4 * MAX_CURSORS
#: most datagrams, and bytes of them (at least one datagram), one :meth:`TuioListener.poll`
#: decodes; the rest stay queued for the next call. A 20-finger frame is about 1.3 kB, a
#: 60 Hz sender's frames come one per poll: a flood cannot hold the polling thread (and
#: the GIL) for seconds
POLL_DATAGRAMS = 32
POLL_BYTES = 16384
#: most bytes of datagrams queued for :meth:`TuioListener.poll` (beside its count bound):
#: sixteen 64 kB datagrams, or 700 frames of 20 fingers; a flood of large datagrams from
#: the served sender is dropped (counted) rather than held in memory
MAX_QUEUED_BYTES = 1 << 20
#: a queued datagram that is not a TUIO frame and has waited this long (s) is dropped
#: unread (counted ``stale``) when a newer one waits behind it, so a backlog of junk
#: drains at once; frames are kept (a sender may send a cursor's set only as it moves)
MAX_QUEUED_S = 0.1
#: largest datagram (bytes) that may claim the input for its sender: a 20-finger frame
#: with its source is about 1.4 kB. A stranger's larger one is refused unparsed, so that
#: refusing a 64 kB bundle of 5,400 messages (10 ms of parsing) costs the haptic process
#: no more than refusing a frame
MAX_CLAIM_BYTES = 4096
#: largest datagram (bytes) decoded from the sender served: a frame of MAX_CURSORS fingers
#: with its source is about 1.4 kB, and a bundle that also carries a tracker's other
#: profiles (2Dobj, 2Dblb) a few kB; a larger one is counted ("too large") unparsed, so
#: that a served sender's flood of 64 kB bundles (10 ms of parsing each) cannot take the
#: haptic process's time
MAX_FRAME_BYTES = 16384
#: one claim parse per sender (address and port) at most this often (s); the datagrams of
#: that sender in between are refused unparsed (a 60 Hz tablet's first frame claims at once)
CLAIM_INTERVAL_S = 0.05
#: most senders whose last claim parse is remembered; beyond, the memory starts afresh
_CLAIM_ADDRESSES = 1024
_CUR_ADDRESS = b"/tuio/2Dcur\0"
_FIRST_ADDRESS = 20  # "#bundle\0", an 8-byte time tag, the first element's 4-byte size


class OscError(TraceError):
    """A malformed OSC packet or TUIO message; the message says where in the packet, and
    ``kind`` names the problem in a few words (a key of :meth:`TuioListener.counters`'
    ``malformed``)."""

    def __init__(self, message: str, kind: str = "not OSC") -> None:
        super().__init__(message)
        self.kind = kind


def _string(data: bytes, pos: int) -> tuple[str, int]:
    end = data.find(b"\0", pos)
    if end < 0:
        raise OscError(f"OSC string at byte {pos} has no NUL terminator")
    try:
        text = data[pos:end].decode("utf-8")
    except UnicodeDecodeError:
        raise OscError(f"OSC string at byte {pos} is not UTF-8: {data[pos:end][:20]!r}") from None
    return text, (end + 4) & ~3


def _take(data: bytes, pos: int, n: int, what: str) -> bytes:
    if pos + n > len(data):
        raise OscError(f"OSC {what} at byte {pos} needs {n} bytes, only {len(data) - pos} left")
    return data[pos:pos + n]


_FIXED = {"i": ">i", "f": ">f", "h": ">q", "d": ">d", "t": ">Q", "c": ">i"}
_EMPTY = {"T": True, "F": False, "N": None, "I": math.inf}


def parse_message(data: bytes) -> tuple[str, list]:
    """One OSC message: ``(address, arguments)`` (see the module grammar)."""
    address, tags, pos = _head(data)
    return address, _arguments(data, address, tags, pos)


def _head(data: bytes) -> tuple[str, str, int]:
    """An OSC message's address, its type tags (without the ','), and the byte where its
    arguments start."""
    address, pos = _string(data, 0)
    if not address.startswith("/"):
        raise OscError(f"OSC address {address[:40]!r} does not start with '/'")
    if pos >= len(data):
        raise OscError(f"OSC message {address} has no type tag string (expected ',...')")
    tags, pos = _string(data, pos)
    if not tags.startswith(","):
        raise OscError(f"OSC message {address}: type tags {tags[:20]!r} do not start with ','")
    return address, tags[1:], pos


def _arguments(data: bytes, address: str, tags: str, pos: int) -> list:
    """The arguments of the message ``address`` typed ``tags``, from byte ``pos``."""
    args: list = []
    for tag in tags:
        if tag in _FIXED:
            fmt = _FIXED[tag]
            size = struct.calcsize(fmt)
            args.append(struct.unpack(fmt, _take(data, pos, size, f"'{tag}' argument"))[0])
            pos += size
        elif tag in "sS":
            text, pos = _string(data, pos)
            args.append(text)
        elif tag == "b":
            (size,) = struct.unpack(">i", _take(data, pos, 4, "blob size"))
            if size < 0:
                raise OscError(f"OSC message {address}: blob size {size} is negative")
            args.append(_take(data, pos + 4, size, "blob"))
            pos += 4 + ((size + 3) & ~3)
        elif tag in "rm":
            args.append(_take(data, pos, 4, f"'{tag}' argument"))
            pos += 4
        elif tag in _EMPTY:
            args.append(_EMPTY[tag])
        else:
            raise OscError(f"OSC message {address}: type tag {tag!r} is not supported "
                           "(expected one of i f s S b h d t c r m T F N I)")
    if pos > len(data):
        raise OscError(f"OSC message {address}: arguments run past the end of the packet")
    return args


def parse_packet(data: bytes) -> list[tuple[str, list]]:
    """All messages of an OSC packet (bundles flattened, in order)."""
    return [parse_message(message) for message in _messages(data)]


def _messages(data: bytes, depth: int = 0) -> list[bytes]:
    """The bytes of each message of an OSC packet (bundles flattened, in order)."""
    if depth > _MAX_DEPTH:
        raise OscError(f"OSC bundles nested more than {_MAX_DEPTH} deep")
    if not data.startswith(b"#bundle\0"):
        return [data]
    _take(data, 8, 8, "bundle time tag")
    pos, out = 16, []
    while pos < len(data):
        (size,) = struct.unpack(">i", _take(data, pos, 4, "bundle element size"))
        if size <= 0 or size % 4:
            raise OscError(f"OSC bundle element at byte {pos} has size {size} "
                           "(expected a positive multiple of 4)")
        out.extend(_messages(_take(data, pos + 4, size, "bundle element"), depth + 1))
        pos += 4 + size
    return out


class TuioDecoder:
    """Incremental 2Dcur decoder: ``feed(packet, t_s)`` returns the samples of the frames it ends.

    Samples are :class:`RawSample` with x, y normalised to 0..1 (TUIO's units) and no
    pressure. Counters: ``frames``, ``late`` (late frames dropped), ``stray`` (set
    messages for sessions not alive, ignored), ``over_limit`` (cursors beyond
    ``MAX_CURSORS`` touching at once or set in one frame, and frames and commands of
    sources beyond ``MAX_SOURCES``, ignored: what the decoder keeps is bounded whatever a
    sender claims, also when it never sends an ``fseq``), ``unread`` (arguments of 2Dcur
    messages after their first ``MAX_ALIVE_IDS + 1``, refused unread: an ``alive``'s ids
    after its first :data:`MAX_ALIVE_IDS`; the work per message is bounded too),
    ``bad_sets`` (``set`` messages that cannot be played, skipped: the rest of their frame
    is played, and a cursor still alive keeps its last good position, as TUIO 1.1's
    ``alive`` says who touches and ``set`` only where; each is given to ``on_bad_set``
    with its sender, "HOST:PORT").
    """

    def __init__(self, on_bad_set: Callable[[OscError, str], None] | None = None) -> None:
        self.frames = self.late = self.stray = self.over_limit = self.unread = self.bad_sets = 0
        self._on_bad_set = on_bad_set
        self._fseq: dict[str, int] = {}
        self._alive: dict[str, set[int]] = {}
        self._pending_alive: dict[str, set[int] | None] = {}
        self._pending_set: dict[str, dict[int, tuple[float, float]]] = {}
        self._waiting_since: dict[str, float] = {}  # source: t of its oldest pending command
        self._pos: dict[tuple[str, int], tuple[float, float]] = {}  # emitted, touching
        self._fingers: dict[tuple[str, int], int] = {}
        self._heard: dict[str, tuple[float, str]] = {}  # source: (last frame's t, origin)

    def feed(self, packet: bytes, t_s: float, origin: str = "") -> list[RawSample]:
        """Decode one UDP datagram received at ``t_s`` (s) from ``origin`` (the sender,
        "HOST:PORT", for :meth:`expire`'s report); a malformed packet (an OscError) changes
        nothing, a bad ``set`` in it is skipped (``bad_sets``)."""
        if len(packet) > MAX_FRAME_BYTES:
            raise OscError(f"{len(packet):,} bytes, over the {MAX_FRAME_BYTES:,} a TUIO frame "
                           f"needs (not decoded)", kind="too large")
        out: list[RawSample] = []
        for command, source, value in _commands(packet):
            if command == "fseq":
                self._commit(source, value, t_s, origin, out)
            elif command == "unread":
                self.unread += value
            elif command == "bad_set":
                self._skip_set(value, origin)
            elif not self._may_hold(source):
                self.over_limit += 1
            else:
                self._waiting_since.setdefault(source, t_s)
                if command == "alive":
                    self._pending_alive[source] = value
                else:
                    self._hold_set(source, *value)
        return out

    def _skip_set(self, error: OscError, origin: str) -> None:
        """Count a ``set`` that cannot be played and hand its ``error`` on."""
        self.bad_sets += 1
        if self._on_bad_set is not None:
            self._on_bad_set(error, origin)

    def _may_hold(self, source: str) -> bool:
        """Whether a command of ``source`` may wait for its frame's ``fseq``: one of the
        sources waiting already, or room for one more (at most ``MAX_SOURCES``)."""
        return source in self._waiting_since or len(self._waiting_since) < MAX_SOURCES

    def _hold_set(self, source: str, sid: int, x: float, y: float) -> None:
        """Keep the ``set`` of cursor ``sid`` until its frame's ``fseq``: at most
        ``MAX_CURSORS`` cursors a source (the others counted over the limit), however
        many sets arrive before an ``fseq`` does, if one ever does."""
        sets = self._pending_set.setdefault(source, {})
        if sid in sets or len(sets) < MAX_CURSORS:
            sets[sid] = (x, y)
        else:
            self.over_limit += 1

    def expire(self, t_s: float, silence_s: float = SILENCE_S,
               speaking: Container[str] = ()
               ) -> tuple[list[RawSample], list[tuple[str, str, int]]]:
        """Forget every source whose last frame is ``silence_s`` s or more before ``t_s``
        and whose origin is not ``speaking`` (a frame of its is yet to be fed): an UP
        sample at ``t_s`` for each of its cursors, its frame number and alive list
        dropped (a restarted sender starts afresh). Returns the samples and, for each
        source that had cursors touching, (origin, source, how many were lifted). Commands
        that have waited ``silence_s`` s for an ``fseq`` are dropped too."""
        out: list[RawSample] = []
        gone: list[tuple[str, str, int]] = []
        for source, since in list(self._waiting_since.items()):
            if t_s - since >= silence_s:
                self._take_pending(source)
        for source, (last, origin) in list(self._heard.items()):
            if t_s - last < silence_s or origin in speaking:
                continue
            del self._heard[source]
            self._fseq.pop(source, None)
            self._alive.pop(source, None)
            self._take_pending(source)
            before = len(out)
            self._lift_gone(source, set(), t_s, out)
            if len(out) > before:
                gone.append((origin, source, len(out) - before))
        return out, gone

    def _commit(self, source: str, fseq: int, t: float, origin: str,
                out: list[RawSample]) -> None:
        alive, sets = self._take_pending(source)
        if not self._admit(source, fseq):
            return
        self.frames += 1
        self._heard[source] = (t, origin)
        if alive is None:
            alive = self._alive.get(source, set())
        self._alive[source] = alive
        self._lift_gone(source, alive, t, out)
        self._apply_sets(source, sets, alive, t, out)

    def _take_pending(self, source: str) -> tuple[set[int] | None, dict]:
        """The ``alive`` ids (None if none came) and the ``set`` positions by id that wait
        for ``source``'s ``fseq``, no longer kept."""
        self._waiting_since.pop(source, None)
        return self._pending_alive.pop(source, None), self._pending_set.pop(source, {})

    def _admit(self, source: str, fseq: int) -> bool:
        """Whether frame ``fseq`` of ``source`` is taken (counting it as over the limit or
        late when not), remembering its frame number."""
        if source not in self._alive and len(self._alive) >= MAX_SOURCES:
            self.over_limit += 1
            return False
        last = self._fseq.get(source)
        if fseq > 0 and last is not None and fseq < last and last - fseq <= _FSEQ_RESTART:
            self.late += 1
            return False
        if fseq > 0:
            self._fseq[source] = fseq
        return True

    def _lift_gone(self, source: str, alive: set, t: float, out: list[RawSample]) -> None:
        """An UP sample for each cursor of ``source`` no longer ``alive``, forgetting it."""
        for key in [k for k in self._pos if k[0] == source and k[1] not in alive]:
            x, y = self._pos.pop(key)
            out.append(RawSample(t, self._fingers.pop(key), x, y, math.nan, math.nan, UP))

    def _apply_sets(self, source: str, sets: dict, alive: set, t: float,
                    out: list[RawSample]) -> None:
        """A DOWN or MOVE sample for each ``set`` of an ``alive`` cursor within the cursor
        limit (counting the others as stray or over the limit)."""
        for sid, (x, y) in sets.items():
            if sid not in alive:
                self.stray += 1
                continue
            key = (source, sid)
            if key not in self._pos and len(self._pos) >= MAX_CURSORS:
                self.over_limit += 1
                continue
            event = MOVE if key in self._pos else DOWN
            if key not in self._fingers:
                self._fingers[key] = self._free_finger()
            self._pos[key] = (x, y)
            out.append(RawSample(t, self._fingers[key], x, y, math.nan, math.nan, event))

    def _free_finger(self) -> int:
        """The lowest finger index no cursor holds."""
        used = set(self._fingers.values())
        return next(i for i in range(len(used) + 1) if i not in used)


def _commands(packet: bytes) -> list[tuple[str, str, object]]:
    """The 2Dcur commands of an OSC packet, checked: (``alive``, source, ids), (``set``,
    source, (id, x, y)), (``fseq``, source, frame), (``bad_set``, source, OscError) for a
    ``set`` that cannot be played (one cursor; the frame stays good), and (``unread``,
    source, how many) for the arguments of a 2Dcur message after its first
    ``MAX_ALIVE_IDS + 1``, refused unread (an ``alive``'s ids after its first
    ``MAX_ALIVE_IDS``). Other addresses are other TUIO profiles or other OSC traffic, and
    are skipped (read as far as that too). Raises OscError for a packet that is not OSC
    or a ``source``, ``alive`` or ``fseq`` that cannot be read: no frame can be trusted."""
    out: list[tuple[str, str, object]] = []
    source = ""
    for message in _messages(packet):
        address, tags, pos = _head(message)
        args = _arguments(message, address, tags[:MAX_ALIVE_IDS + 1], pos)
        if address != "/tuio/2Dcur" or not args:
            continue
        if len(tags) > MAX_ALIVE_IDS + 1:
            out.append(("unread", source, len(tags) - MAX_ALIVE_IDS - 1))
        command = args[0]
        if command == "source":
            source = _arg(args, 1, str, "source")
        elif command == "alive":
            out.append(("alive", source, {_arg(args, i, int, "session id") for i in range(1, len(args))}))
        elif command == "set":
            try:
                out.append(("set", source, _cursor(args)))
            except OscError as exc:
                out.append(("bad_set", source, exc))
        elif command == "fseq":
            out.append(("fseq", source, _arg(args, 1, int, "frame number")))
    return out


def _cursor(args: list) -> tuple[int, float, float]:
    """A 2Dcur ``set``'s session id and normalised position, checked."""
    sid = _arg(args, 1, int, "session id", "cursor arguments wrong")
    x, y = (_arg(args, i, float, "position", "cursor arguments wrong") for i in (2, 3))
    if not (math.isfinite(x) and math.isfinite(y)):
        raise OscError(f"/tuio/2Dcur set {sid}: position ({x!r}, {y!r}) is not finite",
                       "cursor position not finite")
    lo, hi = POSITION_RANGE
    if not (lo <= x <= hi and lo <= y <= hi):
        raise OscError(f"/tuio/2Dcur set {sid}: position ({x:g}, {y:g}) is off the "
                       f"screen, expected {lo:g} to {hi:g} (normalised)",
                       "cursor position off the screen")
    return sid, x, y


def _arg(args: list, i: int, kind: type, what: str, problem: str = "2Dcur arguments wrong"):
    """Argument i of a 2Dcur message, as ``kind`` (an OSC int is accepted as a float);
    an OscError of kind ``problem`` if it is missing or of another type."""
    if i >= len(args):
        raise OscError(f"/tuio/2Dcur {args[0]}: missing {what} (argument {i})", problem)
    value = args[i]
    if isinstance(value, bool) or not isinstance(value, (int, float) if kind is float else kind):
        raise OscError(f"/tuio/2Dcur {args[0]}: {what} is {repr(value)[:40]}, expected "
                       f"{kind.__name__}", problem)
    return kind(value)


def may_be_tuio_frame(data: bytes) -> bool:
    """Whether ``data`` is worth :func:`is_tuio_frame`'s parse, judged from its size and
    first bytes alone: at most :data:`MAX_CLAIM_BYTES`, a bundle whose first element is a
    ``/tuio/2Dcur`` message (as every TUIO 1.1 sender writes its frames)."""
    return (len(data) <= MAX_CLAIM_BYTES and data.startswith(b"#bundle\0")
            and data[_FIRST_ADDRESS:_FIRST_ADDRESS + len(_CUR_ADDRESS)] == _CUR_ADDRESS)


def is_tuio_frame(data: bytes) -> bool:
    """True if ``data`` is an OSC bundle of at most :data:`MAX_CLAIM_BYTES` that starts
    with a ``/tuio/2Dcur`` message, parses and holds a well-formed ``/tuio/2Dcur alive``
    and ``fseq``: a datagram that may claim the first-sender slot. What it costs is
    bounded by the size: a larger datagram is refused unparsed."""
    if not may_be_tuio_frame(data):
        return False
    try:
        commands = {command for command, _, _ in _commands(data)}
    except OscError:
        return False
    return {"alive", "fseq"} <= commands


def exposure_warning(host: str, accept_from: tuple[str, int | None] | None) -> str | None:
    """The one-line warning for a listener on ``host`` beyond loopback that serves the
    first sender (``accept_from`` None); None where there is nothing to warn of."""
    if accept_from is not None or ipaddress.ip_address(host).is_loopback:
        return None
    return (f"warning: TUIO listens on {host} (beyond loopback) and will serve the first "
            "sender of a TUIO frame on the network; name the tablet with --tuio-from ADDR[:PORT]")


#: Linux's SO_TIMESTAMPNS (asm-generic/socket.h; Python's socket module lacks it): the
#: kernel's receive time of each datagram, a struct timespec of two native longs
_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35 if sys.platform.startswith("linux") else None)
_TIMESPEC = struct.Struct("@ll")
#: Linux's SO_RXQ_OVFL (asm-generic/socket.h; Python's socket module lacks it): a datagram
#: carries the socket's running count of datagrams the kernel dropped, its receive buffer
#: full, as a native uint32, once that count is not 0
_SO_RXQ_OVFL = getattr(socket, "SO_RXQ_OVFL", 40 if sys.platform.startswith("linux") else None)
_DROP_COUNT = struct.Struct("@I")
_ANCILLARY_SPACE = socket.CMSG_SPACE(_TIMESPEC.size) + socket.CMSG_SPACE(_DROP_COUNT.size)


def _age_s(ancillary) -> float:
    """How long (s) a datagram waited since the kernel received it, from its
    ``SCM_TIMESTAMPNS`` (wall clock) message; 0 without one (or if the wall clock was
    set back meanwhile)."""
    for level, kind, data in ancillary:  # Linux: SCM_TIMESTAMPNS is SO_TIMESTAMPNS
        if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(data) >= _TIMESPEC.size:
            sec, nsec = _TIMESPEC.unpack(data[:_TIMESPEC.size])
            return max(time.time_ns() - (sec * 1_000_000_000 + nsec), 0) * 1e-9
    return 0.0


def _kernel_drops(ancillary) -> int | None:
    """The socket's count of datagrams the kernel dropped before this one was queued, from
    its ``SO_RXQ_OVFL`` message; None without one (none dropped yet, or not asked)."""
    for level, kind, data in ancillary:
        if level == socket.SOL_SOCKET and kind == _SO_RXQ_OVFL and len(data) >= _DROP_COUNT.size:
            return _DROP_COUNT.unpack(data[:_DROP_COUNT.size])[0]
    return None


def _count_kernel_drops(sock: socket.socket) -> bool:
    """Ask the kernel to tell each datagram's drop count (``SO_RXQ_OVFL``); False where
    the system cannot."""
    if _SO_RXQ_OVFL is None:
        return False
    try:
        sock.setsockopt(socket.SOL_SOCKET, _SO_RXQ_OVFL, 1)
    except OSError:
        return False
    return True


def parse_sender(text: str) -> tuple[str, int | None]:
    """``ADDR`` or ``ADDR:PORT`` (an IPv4 address, a UDP port 1-65535) as (address,
    port), port None for ``ADDR`` alone: then one port of that address is served at a
    time, the first heard, and another takes over only after it has been silent for
    :data:`SILENCE_S` (:class:`SenderGate`). Raises InputError naming what was expected."""
    addr, colon, port_text = text.partition(":")
    try:
        address = str(ipaddress.IPv4Address(addr))
        port = int(port_text) if colon else None
    except ValueError:
        address, port = "", -1
    if not address or (port is not None and not 1 <= port <= 65535):
        raise InputError(f"TUIO sender {text[:60]!r}: expected ADDR or ADDR:PORT, an IPv4 "
                         "address (e.g. 192.168.1.20) and a UDP port 1 to 65535")
    if not _may_send(address):
        raise InputError(f"TUIO sender {address}: no sender has that address (it is "
                         "'any', broadcast or multicast); give the tablet's own address, "
                         "e.g. 192.168.1.20")
    return address, port


_BROADCAST = ipaddress.IPv4Address("255.255.255.255")


def _may_send(address: str) -> bool:
    """Whether a datagram can come from the IPv4 ``address``: not 0.0.0.0 ('any'),
    255.255.255.255 (broadcast) or a multicast group."""
    ip = ipaddress.IPv4Address(address)
    return not (ip.is_unspecified or ip.is_multicast or ip == _BROADCAST)


def unreachable_sender(host: str, accept_from: tuple[str, int | None] | None) -> str | None:
    """Why a listener on ``host`` can never hear the sender ``accept_from`` (a one-line
    message), or None: a socket on loopback only gets datagrams from loopback, so a
    tablet named by its network address could never move a finger."""
    if accept_from is None or not ipaddress.ip_address(host).is_loopback:
        return None
    if ipaddress.ip_address(accept_from[0]).is_loopback:
        return None
    port = "" if accept_from[1] is None else f":{accept_from[1]}"
    return (f"TUIO from {accept_from[0]}{port}: the listener is on loopback ({host}), which "
            f"only hears this machine; listen on the network with --input tuio:0.0.0.0:PORT "
            f"(or tuio:ADDR:PORT, an address of this machine)")


def _name(sender: tuple[str, int]) -> str:
    """A sender as "ADDR:PORT"."""
    return f"{sender[0]}:{sender[1]}"


def _to_stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


class SenderGate:
    """Which UDP sender is served: one at a time, the newest after silence.

    Parameters
    ----------
    accept_from : :func:`parse_sender`'s (address, port or None) to serve only that
        address (with port None: the first of its ports heard, and after that port has
        been silent for ``silence_s``, the next; one port at a time, so that two
        trackers on one host do not move each other's fingers); None: whoever sends a
        TUIO frame first (:func:`is_tuio_frame`), and after that sender has been silent
        for ``silence_s``, whoever sends one next.
    silence_s : how long (s) the served sender must be silent before another may take over.

    ``sender`` is the one served now, (address, port), or None before the first;
    ``takeovers`` counts the times another took over after a silence.
    """

    def __init__(self, accept_from: tuple[str, int | None] | None = None,
                 silence_s: float = SILENCE_S) -> None:
        self.accept_from = accept_from
        self.silence_s = silence_s
        self.sender: tuple[str, int] | None = None
        self.takeovers = 0
        self._last_t = -math.inf
        # (address, port): when its last claim was parsed (s)
        self._claim_t: dict[tuple[str, int], float] = {}

    def _claims(self, sender: tuple[str, int], t_s: float, data: bytes) -> bool:
        """Whether ``data`` from ``sender`` (address, port) at ``t_s`` (s) claims the
        input: a TUIO frame (:func:`is_tuio_frame`), parsed at most once per
        :data:`CLAIM_INTERVAL_S` for each address and port, so that one process's junk
        never delays another's claim (on loopback every process is 127.0.0.1); any other
        datagram, and one in between, is refused unparsed."""
        if not may_be_tuio_frame(data):
            return False
        if t_s - self._claim_t.get(sender, -math.inf) < CLAIM_INTERVAL_S:
            return False
        if len(self._claim_t) >= _CLAIM_ADDRESSES:
            self._claim_t.clear()
        self._claim_t[sender] = t_s
        return is_tuio_frame(data)

    def admit(self, address: str, port: int, t_s: float, data: bytes) -> str | None:
        """Whether the datagram ``data`` from ``address:port`` received at ``t_s`` (s) is
        taken: None (refused), ``"same"`` (the served sender, address and port), ``"new"``
        (the first, or one taking over from a sender silent for ``silence_s`` or more)."""
        named = self.accept_from
        if named is not None and (address != named[0] or named[1] not in (None, port)):
            return None
        if self.sender == (address, port):
            self._last_t = t_s
            return "same"
        if t_s - self._last_t < self.silence_s:
            return None  # another port or sender while the served one speaks
        if named is None and not self._claims((address, port), t_s, data):
            return None
        self.takeovers += self.sender is not None
        self.sender, self._last_t = (address, port), t_s
        return "new"


class TuioListener:
    """Receives TUIO on a UDP port in a thread; :meth:`poll` returns the new touch samples.

    The thread only stamps datagrams as they arrive and queues them (at most
    ``max_packets`` datagrams and ``max_bytes`` bytes; overflow is counted in ``dropped``
    and said once through ``warn``; those the kernel dropped before the thread read them,
    the socket's receive buffer full, in ``kernel_dropped`` where the system says, on
    Linux); decoding happens in :meth:`poll`, on the
    caller's thread, which may block in :meth:`wait` until a datagram is there. One
    :meth:`poll` decodes at most :data:`POLL_DATAGRAMS` datagrams and
    :data:`POLL_BYTES` bytes of them (at least one datagram); the rest wait for the next.
    A datagram that is not a TUIO frame (:func:`may_be_tuio_frame`), queued
    :data:`MAX_QUEUED_S` or longer with a newer one behind it, is dropped unread
    (``stale``); frames are all decoded, as a sender may send a cursor's ``set`` only when
    it moves. Malformed packets are counted in ``bad_packets`` (last
    message in ``last_error``), never raised; a ``set`` that cannot be played is skipped
    (the decoder's ``bad_sets``) and the rest of its frame played. Each kind of problem
    (:class:`OscError`'s ``kind``) is counted in ``malformed`` and said once through
    ``warn``, with its reason, the first time it comes. Datagrams that :class:`SenderGate` refuses
    (another sender while the served one speaks; before one is served, or after it fell
    silent, those that are not a TUIO frame) are counted in ``refused``. A source silent
    for ``silence_s`` s by the clock, with no datagram of its sender that may be a TUIO
    frame (:func:`may_be_tuio_frame`) still queued, has its cursors lifted at the next
    :meth:`poll`, said once through ``warn`` (with how many datagrams came from its
    sender meanwhile, if any did, and how many of them were malformed), however many
    other datagrams are queued.

    Parameters
    ----------
    port : UDP port (TUIO's default 3333; 0 picks a free one, see ``.port``).
    width_mm, height_mm : display size the normalised TUIO coordinates span (mm).
    host : address to bind (default loopback; "0.0.0.0": every interface).
    accept_from : the sender to accept, (IPv4 address, port or None: its first port heard,
        one at a time), as :func:`parse_sender` gives; None: the first sender of a TUIO
        frame (address and port).
    force_n : normal force given to every sample (N); TUIO 1.1 cursors carry none.
    max_packets, max_bytes : queue bounds (datagrams, bytes; :data:`MAX_QUEUED_BYTES`);
        give max_bytes at least 65536 (one datagram of any size), or larger datagrams are
        all dropped as found no room.
    clock : time source for arrival stamps and silences (s).
    silence_s : a source silent this long (s) has gone (:data:`SILENCE_S`).
    warn : takes each one-line notice (a silence, a takeover, a kind of malformed datagram
        the first time, the first queue overflow); default: stderr.
    """

    def __init__(self, port: int = TUIO_PORT, *, width_mm: float, height_mm: float,
                 host: str = TUIO_HOST, accept_from: tuple[str, int | None] | None = None,
                 force_n: float = DEFAULT_FORCE_N, max_packets: int = 1024,
                 max_bytes: int = MAX_QUEUED_BYTES,
                 clock: Callable[[], float] = time.monotonic, silence_s: float = SILENCE_S,
                 warn: Callable[[str], None] | None = None) -> None:
        self.screen = ScreenMap(AxisMap(0.0, 1.0, width_mm), AxisMap(0.0, 1.0, height_mm),
                                force_n=force_n)
        self.decoder = TuioDecoder(on_bad_set=self._bad_set)
        self.dropped = self.bad_packets = self.refused = self.datagrams = self.stale = 0
        self.host = host
        self.gate = SenderGate(accept_from, silence_s)
        self.last_error: str | None = None
        self.malformed: dict[str, int] = {}  # OscError kind: how many
        # origin: (datagrams, malformed ones) decoded since its last frame played
        self._since_frame: dict[str, tuple[int, int]] = {}
        self._clock = clock
        self._warn = warn if warn is not None else _to_stderr
        # (arrival t, queued t, datagram, origin, whether it may be a TUIO frame)
        self._queue: queue.Queue[tuple[float, float, bytes, str, bool]] = queue.Queue(max_packets)
        # origin: how many of its datagrams that may be a TUIO frame are queued, and the
        # bytes queued (never fewer than there are: counted before they are queued,
        # uncounted once taken)
        self._queued_frames: dict[str, int] = {}
        self._queued_bytes = 0
        self._max_bytes = max_bytes
        self._queued_lock = threading.Lock()
        self._ready = threading.Event()
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self._sock.bind((host, port))
        except OSError as exc:
            self._sock.close()
            raise OSError(f"TUIO: cannot listen on UDP {host}:{port} ({exc.strerror})") from None
        self._sock.settimeout(0.05)
        if _SO_TIMESTAMPNS is not None:
            self._sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
        # datagrams the kernel dropped (receive buffer full); None: the system does not say
        self.kernel_dropped: int | None = 0 if _count_kernel_drops(self._sock) else None
        self.port = self._sock.getsockname()[1]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._receive, name=f"tuio-{self.port}", daemon=True)
        self._thread.start()

    def _receive(self) -> None:
        while not self._stop.is_set():
            try:
                data, ancillary, _, (address, port) = self._sock.recvmsg(65536, _ANCILLARY_SPACE)
            except socket.timeout:
                continue
            except OSError:
                return
            drops = _kernel_drops(ancillary)
            if drops is not None:
                self.kernel_dropped = drops
            now = self._clock()
            t = now - _age_s(ancillary)
            before = self.gate.sender
            verdict = self.gate.admit(address, port, t, data)
            if verdict is None:
                self.refused += 1
                continue
            if verdict == "new" and before is not None:
                self._warn(f"TUIO: taking frames from {address}:{port} ({_name(before)} was "
                           f"silent for {self.gate.silence_s:g} s or more)")
            self._enqueue(t, now, data, f"{address}:{port}")

    def _enqueue(self, t: float, now: float, data: bytes, origin: str) -> None:
        """Queue datagram ``data`` from ``origin`` received at ``t`` (s) at ``now`` (s), or
        count it dropped when the queue is full (datagrams or bytes; said the first time);
        counted in ``datagrams`` only then, so that a reader who sees the count can
        :meth:`poll` the datagram."""
        frame = may_be_tuio_frame(data)
        queued = self._count_queued(origin, frame, len(data), +1)
        try:
            if not queued:
                raise queue.Full
            self._queue.put_nowait((t, now, data, origin, frame))
        except queue.Full:
            if queued:
                self._count_queued(origin, frame, len(data), -1)
            self._drop(origin)
        self._ready.set()
        self.datagrams += 1

    def _drop(self, origin: str) -> None:
        """Count a datagram of ``origin`` dropped, the queue being full; said the first time."""
        if not self.dropped:
            self._warn(f"TUIO: datagrams from {origin} come faster than they are decoded "
                       f"({self._queue.maxsize} datagrams or {self._max_bytes // 1024} kB "
                       "queued): dropping; further ones counted")
        self.dropped += 1

    def _take(self) -> tuple[float, float, bytes, str, bool] | None:
        """The oldest queued datagram (as queued), no longer counted queued; None if none."""
        try:
            item = self._queue.get_nowait()
        except queue.Empty:
            return None
        self._count_queued(item[3], item[4], len(item[2]), -1)
        return item

    def _count_queued(self, origin: str, frame: bool, size: int, sign: int) -> bool:
        """Count a datagram of ``size`` bytes from ``origin`` (``frame``: one that may be a
        TUIO frame) as queued (``sign`` +1) or taken (-1), between the receiving thread
        and the polling one; False, counting nothing, if queuing it would pass the
        byte bound."""
        with self._queued_lock:
            if sign > 0 and self._queued_bytes + size > self._max_bytes:
                return False
            self._queued_bytes += sign * size
            count = self._queued_frames.get(origin, 0) + sign * frame
            if count:
                self._queued_frames[origin] = count
            else:
                self._queued_frames.pop(origin, None)
        return True

    def _speaking(self) -> set[str]:
        """The origins with a datagram that may be a TUIO frame still queued: not silent,
        whatever the clock says, as that frame may keep their cursors touching."""
        with self._queued_lock:
            return set(self._queued_frames)

    def wait(self, timeout_s: float) -> bool:
        """Block until a datagram arrived since the last :meth:`poll`, at most
        ``timeout_s`` s; True if one did."""
        return self._ready.wait(timeout_s)

    def poll(self) -> list[TouchSample]:
        """Samples of the frames received since the last call (mm, N, s), in order, from
        at most :data:`POLL_DATAGRAMS` datagrams and :data:`POLL_BYTES` bytes of them (at
        least one): with more queued, :meth:`wait` returns at once for the rest. Stale
        datagrams are dropped unread; sources silent by the clock, with no frame of their
        sender still queued, are lifted last."""
        self._ready.clear()  # before draining: a datagram queued meanwhile sets it again
        raw: list[RawSample] = []
        datagrams, size, now = 0, 0, self._clock()
        while datagrams < POLL_DATAGRAMS and size < POLL_BYTES:
            item = self._take()
            if item is None:
                break
            t, queued_t, data, origin, frame = item
            if now - queued_t >= MAX_QUEUED_S and not self._queue.empty() and not frame:
                self.stale += 1  # kept if a frame: it may hold a touch's only set
                continue
            datagrams, size = datagrams + 1, size + len(data)
            raw.extend(self._decode(t, data, origin))
        raw.extend(self._expire(self._clock(), self._speaking()))
        if not self._queue.empty():
            self._ready.set()
        return self.screen.touches(raw)

    def _decode(self, t: float, data: bytes, origin: str) -> list[RawSample]:
        """The samples of datagram ``data`` from ``origin`` received at ``t`` (s), after
        those lifting the sources silent by then; a malformed one counted."""
        raw = self._expire(t)
        frames, malformed = self.decoder.frames, False
        try:
            raw.extend(self.decoder.feed(data, t, origin))
        except OscError as exc:
            self.bad_packets, malformed = self.bad_packets + 1, True
            self._note(exc, f"TUIO: malformed datagram from {origin}: {exc}; further ones counted")
        self._count_since_frame(origin, self.decoder.frames > frames, malformed)
        return raw

    def _bad_set(self, error: OscError, origin: str) -> None:
        """A ``set`` from ``origin`` skipped by the decoder: counted, said the first time."""
        self._note(error, f"TUIO: cursor skipped in a frame from {origin}: {error} (the "
                          "frame's other cursors played, this one kept where it was); "
                          "further ones counted")

    def _note(self, error: OscError, line: str) -> None:
        """Count ``error`` under its kind in ``malformed``, keep it in ``last_error``, and
        say ``line`` the first time its kind comes."""
        if error.kind not in self.malformed:
            self._warn(line)
        self.malformed[error.kind] = self.malformed.get(error.kind, 0) + 1
        self.last_error = str(error)

    def _count_since_frame(self, origin: str, played: bool, malformed: bool) -> None:
        """Count a datagram of ``origin`` decoded (``malformed`` or not) since its last
        frame played, or forget the count when this one ``played`` a frame."""
        if played:
            self._since_frame.pop(origin, None)
            return
        datagrams, bad = self._since_frame.get(origin, (0, 0))
        self._since_frame[origin] = (datagrams + 1, bad + malformed)

    def _expire(self, t: float, speaking: Container[str] = ()) -> list[RawSample]:
        """UP samples for the cursors of sources silent at ``t`` (s), but those of the
        origins ``speaking``, each said once."""
        lifted, gone = self.decoder.expire(t, self.gate.silence_s, speaking)
        for origin, source, n in gone:
            named = f" (source {quoted(source)})" if source else ""  # escaped and cut: a sender's
            missing, came = self._silence(origin)
            self._warn(f"TUIO: no {missing} from {origin}{named} for {self.gate.silence_s:g} s"
                       f"{came}: lifted {n} finger{'s' if n != 1 else ''}")
        return lifted

    def _silence(self, origin: str) -> tuple[str, str]:
        """For the silence line of ``origin``, what did not come ("message", or "valid
        frame" when datagrams came but none played a frame) and what did since its last
        frame (" (N datagrams, M malformed)", or ""); that count is then forgotten."""
        datagrams, malformed = self._since_frame.pop(origin, (0, 0))
        if not datagrams:
            return "message", ""
        return "valid frame", (f" ({datagrams} datagram{'s' if datagrams != 1 else ''}, "
                               f"{malformed} malformed)")

    def counters(self) -> dict:
        """What was received: ``datagrams`` accepted, ``refused`` (other senders, or
        before one was served), ``kernel_dropped`` (by the kernel, the socket's receive
        buffer full, as the last datagram received said; None where the system does not
        say), ``dropped`` (queue full), ``stale`` (dropped unread, a
        newer one queued), ``bad_packets`` (malformed datagrams), the decoder's
        ``bad_sets`` (cursors skipped), ``malformed`` (how many of each kind of problem
        of those two, by :class:`OscError` kind), the decoder's ``late``, ``stray``,
        ``over_limit`` and ``unread``, ``takeovers`` (senders served after another fell
        silent), and the ``sender`` served last ("ADDR:PORT", or None before the first)."""
        sender = None if self.gate.sender is None else _name(self.gate.sender)
        return {"listen": f"{self.host}:{self.port}", "sender": sender,
                "datagrams": self.datagrams, "refused": self.refused,
                "kernel_dropped": self.kernel_dropped, "dropped": self.dropped,
                "stale": self.stale,
                "bad_packets": self.bad_packets, "bad_sets": self.decoder.bad_sets,
                "malformed": dict(self.malformed), "late": self.decoder.late,
                "stray": self.decoder.stray, "over_limit": self.decoder.over_limit,
                "unread": self.decoder.unread,
                "takeovers": self.gate.takeovers}

    def close(self) -> None:
        """Stop the thread and release the port."""
        self._stop.set()
        self._thread.join()
        self._sock.close()

    def __enter__(self) -> TuioListener:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

"""``frictex sim-device``: a simulated plate microcontroller on a pseudo-terminal or TCP.

Prints where a host reaches it as the first line on stdout (the pty's path, or
``socket://HOST:PORT`` with ``--tcp``), then speaks the device side of
``device/PROTOCOL.md`` to host after host until Ctrl-C (or, with ``--once``, until the
first host's Stop has played out). Ctrl-C closes the port and the logs, prints what was
played, then ends as every command does: ``frictex: interrupted``, exit 130 (SIGTERM
ends it as a finished run, exit 0).

One host at a time: over TCP, a connection made while a host is connected is refused
(it gets an ErrorReport saying the device is busy and is closed, a line on stderr says
so); it never takes the stream over. The next host is served once the current one has
hung up. The protocol has no field for a shared secret: keep the listener on loopback
(the default) or a network only trusted hosts reach. For tools outside frictex: the host's
own ``--device sim`` runs the simulated device in its process and needs none of this.
"""

from __future__ import annotations

import argparse
import os
import select
import signal
import subprocess
import sys
import threading
import time

from frictex.app.commands.argtypes import bounded, positive_float, positive_int
from frictex.device.errors import DeviceError
from frictex.device.link.simdevice import (HELLO_TIMEOUT_S, MAX_CHANNELS, STORE_WORDS, DeviceConfig,
                                           DeviceCore, host_port, open_listener, open_pty,
                                           played_log, plate_log, plate_log_growth, serve,
                                           socket_url)
from frictex.device.safe_text import escape_path


def _tcp_address(text: str) -> tuple[str, int]:
    """``PORT`` or ``HOST:PORT`` (port 0: any free port), an IPv6 host in brackets
    (``[::1]:PORT``); the host is returned without them."""
    host, _, port = text.rpartition(":")
    try:
        number = int(port)
    except ValueError:
        number = -1
    if not 0 <= number <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r}: expected PORT or HOST:PORT, port in "
                                         "0..65535 (0: any free port)")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    elif ":" in host or "[" in host or "]" in host:
        raise argparse.ArgumentTypeError(f"{text!r}: an IPv6 address is written in "
                                         "brackets, [ADDRESS]:PORT")
    return host or "127.0.0.1", number


def _log_path(text: str) -> str:
    """A log file's path; an empty one is refused (it would mean no log, silently)."""
    if not text:
        raise argparse.ArgumentTypeError("an empty path; give a file to write, or leave the "
                                         "option out for no log")
    return text


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--channels", type=bounded(int, 1, MAX_CHANNELS, "channels"), default=1,
                        metavar="N", help=f"actuator channels, 1 to {MAX_CHANNELS} as the "
                                          "firmware (default 1)")
    parser.add_argument("--rate", type=positive_float, default=10_000.0, metavar="HZ",
                        help="sample rate the device plays at (default 10000 Hz, seed 003)")
    parser.add_argument("--limit", type=positive_float, action="append", metavar="UM",
                        help="amplitude limit in um zero-to-peak, declared to the host; once for "
                             "all channels or once per channel (default 4.0)")
    parser.add_argument("--buffer", type=positive_int, default=4096, metavar="N",
                        help=f"jitter-buffer capacity in samples, 2 to {STORE_WORDS} / channels "
                             "as the firmware (default 4096)")
    parser.add_argument("--bandwidth", type=positive_float, default=400.0, metavar="HZ",
                        help="corner frequency of the modelled amplitude loop, a first-order "
                             "low pass (default 400 Hz, seed 003 Fig. 3b); -3 dB there only "
                             "where it is well under --rate (PROTOCOL.md 5.4)")
    parser.add_argument("--watchdog-ms", type=bounded(int, 1, 49, "ms"), default=25, metavar="MS",
                        help="host silence that trips the watchdog (default 25 ms; with the ramp "
                             "at most 50 ms)")
    parser.add_argument("--ramp-ms", type=int, default=20, metavar="MS",
                        help="ramp to zero after a trip, a stop, a Hello or a hold of "
                             "watchdog_ms without a sample to play, 0 to 50 - watchdog_ms "
                             "(default 20 ms)")
    parser.add_argument("--phases", action="store_true", help="accept a phase per channel")
    parser.add_argument("--sensor", action="store_true",
                        help="report the modelled plate amplitude as 'measured'")
    parser.add_argument("--force", type=float, default=None, metavar="N",
                        help="report this normal force (N) from a simulated force sensor")
    parser.add_argument("--lateral", type=float, default=None, metavar="N",
                        help="send force reports (protocol 3 or later) of this constant lateral "
                             "force (N) and the --force normal force (0 without)")
    parser.add_argument("--finger", type=int, default=None, metavar="SEED",
                        help="send force reports (protocol 3 or later) from a simulated finger, "
                             "person SEED (>= 0) of device.finger's population, sliding at "
                             "--finger-speed and pressing with --force (default 0.5 N): "
                             "friction of the played amplitude by seed 003's model with that "
                             "person's constants and drift, seen by a 1 kHz sensor with 2 mN "
                             "lateral and 5 mN normal noise (device/finger.py)")
    parser.add_argument("--finger-speed", type=float, default=100.0, metavar="MM_S",
                        help="sliding speed of the --finger (default 100 mm/s; negative: "
                             "towards -x, its lateral force negative, PROTOCOL.md 4.9)")
    parser.add_argument("--log", type=_log_path, metavar="CSV", default=None,
                        help="write every played sample: index,ch0_um,... (fixed-point values)")
    rows, mb_hour = plate_log_growth(1, 10_000.0)
    parser.add_argument("--plate-log", type=_log_path, metavar="CSV", default=None,
                        help="write every tick: t_s,state,ch<k>_setpoint_um,ch<k>_plate_um; "
                             "it grows while the device runs, with or without a host: one "
                             f"row per tick, {rows:,.0f} rows a second, about "
                             f"{mb_hour:,.0f} MB an hour at the default rate with one channel "
                             f"and {24 * 3600 * rows / 1e6:,.0f} MB an hour more per further "
                             "channel (measured: 4.2 MB in its first 12 s, 35 bytes a row, "
                             "38 once t_s passes 1000 s); a line on stderr gives the rate")
    parser.add_argument("--tcp", type=_tcp_address, default=None, metavar="[HOST:]PORT",
                        help="listen on TCP instead of a pty (host default 127.0.0.1, an IPv6 "
                             "address in brackets: [::1]:0; port 0: any free port); hosts open the printed socket:// URL, one at a "
                             "time: a second connection is refused while one is connected, "
                             "and one that says no Hello within 2 s, or sends nothing for 5 s after "
                             "it, is dropped")
    parser.add_argument("--protocol", type=int, choices=(1, 2, 3, 4), default=4,
                        help="newest protocol version to speak (default 4, with repair of "
                             "lost frames; 1 to 3 act as firmware of that version)")
    parser.add_argument("--once", action="store_true",
                        help="exit once the first host's Stop has played out (default: serve "
                             "host after host until Ctrl-C)")
    parser.add_argument("--parent-pid", type=positive_int, default=None, help=argparse.SUPPRESS)


def run(args: argparse.Namespace) -> int:
    limits = tuple(args.limit) if args.limit else (4.0,)
    config = DeviceConfig(channels=args.channels, rate_hz=args.rate, limits_um=limits,
                          buffer_samples=args.buffer, bandwidth_hz=args.bandwidth,
                          watchdog_ms=args.watchdog_ms, ramp_ms=args.ramp_ms,
                          phases=args.phases, sensor=args.sensor, force_n=args.force,
                          protocol_version=args.protocol, lateral_n=args.lateral,
                          finger=args.finger, finger_speed_mm_s=args.finger_speed)
    core = DeviceCore(config)
    quit_event = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: quit_event.set())
    try:
        lost = _serve_logged(core, args, quit_event)
    except KeyboardInterrupt:  # port and logs closed: the counts, then the command line's
        _print_counts(core)    # 'frictex: interrupted', exit 130
        raise
    _print_counts(core)
    if lost:  # its warning said which and why when it happened
        print(f"frictex: error: {', '.join(lost)}: logging stopped early (said above)",
              file=sys.stderr)
        return 1
    return 0


def _serve_logged(core: DeviceCore, args: argparse.Namespace,
                  quit_event: threading.Event) -> list[str]:
    """:func:`_serve`, with the ``--log`` and ``--plate-log`` files open (closed whatever
    ends it); the options whose log a write the file system refused ended early."""
    config, logs = core.config, []
    try:
        if args.log is not None:
            core.log, csv = played_log(args.log, config.channels, config.phases)
            logs.append(csv)
        if args.plate_log is not None:
            core.plate_log, csv = plate_log(args.plate_log, config.channels)
            logs.append(csv)
            rows, mb_hour = plate_log_growth(config.channels, config.rate_hz)
            print(f"frictex sim-device: --plate-log {escape_path(args.plate_log)} grows by "
                  f"{rows:,.0f} rows a second, about {mb_hour:,.0f} MB an hour, until the "
                  "device exits",
                  file=sys.stderr)
        _serve(core, args, quit_event)
    finally:
        for csv in logs:
            csv.close()
    return [option for option, csv in zip(("--log", "--plate-log"), logs) if csv.lost]


def _print_counts(core: DeviceCore) -> None:
    """What the device played and what went wrong, on stderr."""
    k = core.counters
    print(f"frictex sim-device: played {k.played_samples} samples; {k.underruns} underruns, "
          f"{core.decoder.counts.discarded} bad frames, {k.watchdog_trips} watchdog trips",
          file=sys.stderr)


def _serve(core: DeviceCore, args: argparse.Namespace, quit_event: threading.Event) -> None:
    """Open the pty or the TCP listener, say where, and serve until told to stop."""
    def refused(address, count):
        more = f" and {count - 1} more in the last second" if count > 1 else ""
        print(f"frictex sim-device: refused a second host {host_port(*address[:2])}{more} "
              "(one host at a time)", file=sys.stderr)

    def dropped(address):
        print(f"frictex sim-device: dropped host {host_port(*address[:2])}: no Hello within "
              f"{HELLO_TIMEOUT_S:g} s of connecting", file=sys.stderr)
    options = {"exit_on_stop": args.once, "parent_pid": args.parent_pid,
               "quit_event": quit_event, "on_refused": refused, "on_dropped": dropped}
    if args.tcp is not None:
        listener = open_listener(*args.tcp)
        where, close = socket_url(listener), listener.close
        target = {"listener": listener}
    else:
        master, slave, where = open_pty()
        target = {"master": master}

        def close():
            os.close(master)
            os.close(slave)
    try:
        print(where, flush=True)
        print(f"frictex sim-device: {core.config.channels} channel(s) at "
              f"{core.config.rate_hz:g} Hz on {where}; Ctrl-C to quit", file=sys.stderr)
        serve(core, **target, **options)
    finally:
        close()


#: longest a sim-device that neither prints where it is nor exits is waited for (s): a
#: hang, not a busy machine
HANG_S = 120.0


def spawn(channels: int = 1, rate_hz: float = 10_000.0, *, tcp: bool = False,
          extra: tuple[str, ...] = ()) -> tuple[subprocess.Popen, str]:
    """Start ``frictex sim-device --once`` in a process of its own (as an external tool
    would run it) on a new pty, or with ``tcp`` a loopback TCP port; returns (process,
    pty path or ``socket://`` URL), which the host opens like any port. ``extra``: more
    flags (``--log CSV``, ``--finger 3``...). It ends when its host's Stop has played out
    or this process is gone. Waited for as long as it runs (at most :data:`HANG_S`);
    raises DeviceError if it exits or hangs first."""
    cmd = [sys.executable, "-m", "frictex", "sim-device", "--once", "--channels",
           str(channels), "--rate", repr(float(rate_hz)), "--parent-pid", str(os.getpid()),
           *(["--tcp", "0"] if tcp else []), *extra]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    line, deadline = "", time.monotonic() + HANG_S
    while time.monotonic() < deadline and proc.poll() is None:
        if select.select([proc.stdout], [], [], 0.5)[0]:
            line = proc.stdout.readline().strip()
            break
    if not line.startswith(("/", "socket://")):
        proc.kill()
        proc.wait(timeout=5.0)
        raise DeviceError(f"frictex sim-device did not start (printed {line!r}; exit code "
                          f"{proc.poll()})")
    return proc, line

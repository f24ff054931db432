"""Regenerate traces/two-fingers-crossing-50hz.csv, the two-finger replay trace (deterministic).

Two fingers on the 350 mm beam of two-finger-beam-seed000 (y = 3 mm, mid-width), sampled
at 50 Hz like seed 003's screen: finger 0 touches at 110 mm and slides right at 15 mm/s
for 4.4 s; finger 1 touches 0.2 s later at 260 mm and slides left at 40 mm/s for 4 s.
They cross near x = 153 mm at t = 2.87 s (coincident fingers: det Phi = 0), and on the
way their pair crosses the other loci where det Phi of modes 16 and 17 changes sign
(seed 000, Fig. 8), about every 10 mm of relative travel. Regenerate the bundled file with:

    .venv/bin/python -m frictex.rendering.input.two_finger_trace
"""

import numpy as np

from frictex.rendering.input.trace_synth import make_motion, sample
from frictex.rendering.input.trace_file import make_trace, write_trace
from frictex.textures.library import LIBRARY_DIR

RATE_HZ = 50.0
Y_MM = 3.0
#: (finger, touch-down time s, start x mm, speed mm/s, direction deg, duration s)
FINGERS = ((0, 0.0, 110.0, 15.0, 0.0, 4.4), (1, 0.2, 260.0, 40.0, 180.0, 4.0))


def two_finger_trace():
    """Both fingers' samples merged in time order (a Trace)."""
    parts = []
    for finger, t0, x0, speed, angle, duration in FINGERS:
        motion = make_motion("swipe", speed_mm_s=speed, duration_s=duration, x0_mm=x0,
                             y0_mm=Y_MM, angle_deg=angle)
        parts.append((t0, sample(motion, RATE_HZ, finger=finger)))
    t = np.concatenate([tr.t_s + t0 for t0, tr in parts])
    order = np.argsort(t, kind="stable")
    cols = [np.concatenate([getattr(tr, name) for _, tr in parts])[order]
            for name in ("finger", "x_mm", "y_mm", "force_n", "event")]
    return make_trace(t[order], *cols)


def description() -> str:
    return ("two fingers crossing on the seed 000 beam, 50 Hz: finger 0 from 110 mm right at "
            "15 mm/s, finger 1 from 260 mm left at 40 mm/s, crossing at 153 mm "
            "(python -m frictex.rendering.input.two_finger_trace)")


def main(argv: list[str] | None = None) -> None:
    """Write the trace to ``-o`` (default: the bundled file)."""
    import argparse
    bundled = LIBRARY_DIR / "traces" / "two-fingers-crossing-50hz.csv"
    parser = argparse.ArgumentParser(prog="python -m frictex.rendering.input.two_finger_trace",
                                     description="write the two-finger replay trace "
                                                 "(deterministic)")
    parser.add_argument("-o", "--out", default=str(bundled),
                        help="the file to write (default: the bundled %(default)s)")
    out = parser.parse_args(argv).out
    write_trace(out, two_finger_trace(), comment=description())
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

"""A trace's last sample before a long gap touches as any sample does, and a --max-gap
under the trace's sampling interval is warned about."""

import json

from frictex.app.engine.replay import run_replay
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene


def contact_samples(tmp_path, rows: str, name: str, **options) -> tuple[int, list[str]]:
    """Finger 0's contact samples in the replay of trace ``rows``, and its warnings."""
    trace = tmp_path / f"{name}.csv"
    trace.write_text("t_s,finger,x_mm,y_mm\n" + rows)
    doc = run_replay(load_scene(resolve_scene("grating-5mm")), str(trace), tmp_path / name,
                     progress=False, **options)
    written = json.loads((tmp_path / name / "summary.json").read_text())
    return written["fingers"]["0"]["contact_samples"], doc["warnings"]


def test_a_sample_before_a_long_gap_gets_its_block_of_contact(tmp_path):
    alone, _ = contact_samples(tmp_path, "0,0,1,1\n", "alone")
    both, warnings = contact_samples(tmp_path, "0,0,1,1\n6,0,2,1\n", "gap")
    assert alone > 0 and both == 2 * alone
    assert any("taken as lifts" in line for line in warnings)


def test_a_max_gap_under_the_median_sample_interval_is_warned(tmp_path):
    rows = "".join(f"{0.01 * k:.2f},0,{1 + 0.1 * k:.1f},1\n" for k in range(20))
    _, kept = contact_samples(tmp_path, rows, "kept", max_gap_s=0.02)
    _, lifted = contact_samples(tmp_path, rows, "lifted", max_gap_s=0.005)
    assert not any("median sample interval" in line for line in kept)
    assert any("median sample interval (0.01 s)" in line for line in lifted)

"""``frictex report``: the quick matrix's ranking claims, the hybrid's standing, the files."""

import json

import pytest

from app.commands.cli import main
from app.measure.report_claims import claims
from app.measure.report_matrix import Runner, matrix
from app.measure.report_output import pareto

#: the one hybrid target that does not hold: time error on the 0.6 mm grating under the
#: human-like motion, a phase no finger feels and no renderer gets right while the finger
#: moves (the numbers are in rendering/layers/hybrid.py's docstring); any other miss fails
KNOWN_SHORTFALLS = {
    ("hybrid-best", "grating-0.6mm", "human", "time_error"),
    ("hybrid-30", "grating-0.6mm", "human", "time_error"),
}


@pytest.fixture(scope="module")
def grating_rows():
    runner = Runner(live_s=0.02)
    cases = [c for c in matrix(quick=True, scenes=("grating-15mm", "grating-5mm", "grating-0.6mm"))
             if c.output_hz == 10_000.0 and c.inversion == "exact"]
    return [runner.run(c) for c in cases]


def test_plain_sho_against_sht_reproduces_seed_003(grating_rows):
    """SHT beats SHO on the spectrum at 0.6 mm, SHO beats SHT on alignment at 15 mm, for
    the constant-speed and human-like motions at 50 Hz."""
    ranking = [c for c in claims(grating_rows) if c.group == "ranking"]
    assert len(ranking) == 6
    assert all(c.passed for c in ranking), [c.text for c in ranking if not c.passed]


def test_hybrid_claims_hold_except_the_known_shortfalls(grating_rows):
    hybrid = [c for c in claims(grating_rows) if c.group.startswith("hybrid")]
    assert len(hybrid) == 2 * 27
    failing = {(c.group, c.scene, c.motion, c.metric) for c in hybrid if not c.passed}
    assert failing <= KNOWN_SHORTFALLS, failing - KNOWN_SHORTFALLS
    # the alignment the eye checks and the spectrum the finger feels are never worse than
    # either, on any grating or motion
    assert all(c.passed for c in hybrid if c.metric != "time_error")


def test_rows_have_the_documented_fields(grating_rows):
    row = grating_rows[0]
    for key in ("scene", "period_mm", "motion", "touch_hz", "renderer", "output_hz",
                "time_error", "spectral_error", "alignment_error_mm", "cost_us_per_s"):
        assert key in row
    assert set(row["throughput"]) == {"replay_x_realtime", "live_block_p99_us", "latency_ms"}
    assert {"tracking", "layer:lines", "composition", "inversion", "actuation"} <= set(row["stages_us_per_s"])
    assert row["period_mm"] == 15.0
    # latency: at most one 5 ms block of waiting plus the link's 20 ms buffer
    assert 20.0 <= row["throughput"]["latency_ms"] <= 25.0


def test_seed_scatter_counts_hybrid_wins_per_draw():
    from app.measure.report_seeds import _wins
    per = {"hybrid": {"m": [1.0, 2.0, None, 0.5]}, "sho-held": {"m": [1.0, 1.0, 3.0, None]},
           "sht": {"m": [2.0, 3.0, 1.0, None]}}
    assert _wins(per, "m") == 3  # ties win; an undefined hybrid value or no rival: a win


def test_pareto_front():
    pts = [(1.0, 5.0), (2.0, 3.0), (3.0, 3.0), (4.0, 1.0), (5.0, 2.0)]
    assert pareto(pts) == [True, True, False, True, False]


def test_report_writes_its_files(tmp_path, capsys):
    out = tmp_path / "rep"
    assert main(["report", "--quick", "--scenes", "grating-15mm", "--out", str(out),
                 "--no-progress"]) == 0
    doc = json.loads((out / "report.json").read_text())
    assert {r["renderer"] for r in doc["rows"]} == {"sho-held", "sho-predicted", "sht", "hybrid"}
    assert {r["output_hz"] for r in doc["rows"]} == {2000.0, 5000.0, 10_000.0, 20_000.0}
    assert (out / "error_vs_cost.png").stat().st_size > 10_000
    assert (out / "error_vs_period.png").stat().st_size > 10_000
    markdown = (out / "report.md").read_text()
    assert "## Physical limits" in markdown and "## Seed scatter" in markdown
    # two fingers with modal actuation: measured, with its stages
    assert doc["modal_replay"]["replay_x_realtime"] > 0
    assert doc["modal_replay"]["stages_us_per_s"]["actuation"] > 0
    scatter = doc["seed_scatter"]
    assert scatter["seeds"] == [1, 2, 3, 4] and set(scatter["values"]) == {"grating-15mm"}
    assert all(len(v) == 4 for per in scatter["values"]["grating-15mm"].values() for v in per.values())
    assert "claims hold" in capsys.readouterr().out
    # issue 5: each modal inversion method's speed and error, measured
    modal = {f["label"]: f["value"] for f in doc["modal_inversion"]}
    for method in ("exact", "regularised", "bounded"):
        assert modal[f"{method} random: time per sample (blocks of 50)"] > 0
        assert 0 <= modal[f"{method} near-singular: mean error"] < 0.5
    # the default stays continuous across a singular locus; the exact inverse jumps
    assert (modal["regularised: largest command step, finger b crossing a in 1 um steps"]
            < 0.01 < modal["exact: largest command step, finger b crossing a in 1 um steps"])


@pytest.mark.parametrize("argv, message", [
    (["report", "--scenes", "grating-7mm"], "--scenes: unknown scene(s) grating-7mm"),
])
def test_bad_input_is_one_line_and_exit_2(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: ") and message in err and err.count("\n") == 1


def test_out_that_is_a_file_is_refused(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["report", "--quick", "--out", str(f)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err

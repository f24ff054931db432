"""What the live demo says about what it did: a headless demo's synthesized stroke lasts
--duration."""

import json

from frictex.app.commands.cli import main


def test_a_headless_demo_strokes_for_its_duration(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    out = tmp_path / "out"
    assert main(["demo", "grating-0.6mm", "--headless", "--haptic", "thread",
                 "--duration", "4.5", "--out", str(out)]) == 0
    assert "a synthesized stroke of 4.5 s drove the mouse" in capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["output_s"] >= 4.5 and summary["ended_by"] == "window"

"""A window session on a machine without a display says how to go on: it said only 'no
display (DISPLAY and WAYLAND_DISPLAY are unset)', where the demo names its alternatives."""

from frictex.app.commands.cli import main


def test_a_window_participant_without_a_display_names_the_simulated_one(tmp_path, capsys,
                                                                         monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    out = tmp_path / "w1"
    assert main(["experiment", "period-2afc", "--participant", "window", "--out",
                 str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: no display") and err.count("\n") == 1
    assert "a window participant needs one" in err and "--participant simulated:" in err
    assert not out.exists()

"""A protocol's scene is checked under each stimulus's own renderer: seed003-gratings
plays the 0.6 mm grating with SHO-held (aliased) and SHT (felt), and each note names
its stimulus."""

from pathlib import Path

from frictex.app.experiment.perception_check import protocol_findings
from frictex.app.experiment.protocol import load_protocol

PROTOCOLS = Path(__file__).resolve().parents[1] / "app" / "experiment" / "protocols"


def test_each_stimulus_is_checked_with_its_own_renderer():
    found = protocol_findings(load_protocol(PROTOCOLS / "seed003-gratings.toml"))
    touch = [f.message for f in found if f.kind == "touch"]
    assert len(touch) == 2
    held, sht = touch
    assert held.startswith('grating-0.6mm.toml (stimulus "0.6mm-sho"): ')
    assert "SHO-held reads the map only at each touch sample and aliases it" in held
    assert sht.startswith('grating-0.6mm.toml (stimulus "0.6mm-sht"): ')
    assert "SHT plays" in sht and "hybrid" not in sht.split(": ", 1)[1].split("aliases")[0]


def test_a_note_alike_for_several_stimuli_is_given_once_naming_them(tmp_path):
    (tmp_path / "p.toml").write_text(
        'format = 1\nmethod = "magnitude"\n'
        '[[stimulus]]\nname = "a"\nscene = "grating-0.6mm"\nrenderer = "sht"\n'
        '[[stimulus]]\nname = "b"\nscene = "grating-0.6mm"\nrenderer = "sht"\n',
        encoding="utf-8")
    touch = [f.message for f in protocol_findings(load_protocol(tmp_path / "p.toml"))
             if f.kind == "touch"]
    assert len(touch) == 1 and touch[0].startswith('grating-0.6mm.toml (stimuli "a", "b"): ')

"""An AHAP file's structural errors name JSON's kinds (object, array, string, number,
true/false, null), not Python's, and a key that is not there reads as missing."""

import json

import pytest

from frictex.textures.ahap import parse_ahap
from frictex.textures.errors import TextureError

TICK = {"Event": {"Time": 0.0, "EventType": "HapticTransient"}}


@pytest.mark.parametrize("doc, said", [
    ({"Version": 1}, "AHAP: Pattern: missing"),
    ({"Pattern": {}}, "AHAP: Pattern: expected an array, got an object"),
    ({"Pattern": None}, "AHAP: Pattern: expected an array, got null"),
    ({"Pattern": "tick"}, "AHAP: Pattern: expected an array, got a string"),
    ({"Pattern": 1.5}, "AHAP: Pattern: expected an array, got a number"),
    ({"Pattern": True}, "AHAP: Pattern: expected an array, got true"),
    ({"Pattern": [[TICK]]}, "AHAP: Pattern[0]: expected an object, got an array"),
    ({"Pattern": [{"Event": False}]}, "AHAP: Pattern[0].Event: expected an object, got false"),
    ([TICK], "AHAP: top level: expected an object, got an array"),
    ({"Pattern": [TICK, {"ParameterCurve": {"ParameterID": "HapticIntensityControl",
                                            "Time": 0.0}}]},
     "AHAP: Pattern[1].ParameterCurve.ParameterCurveControlPoints: missing"),
])
def test_a_structural_error_names_the_json_kind(doc, said):
    with pytest.raises(TextureError) as refused:
        parse_ahap(json.dumps(doc), 0.3)
    assert str(refused.value) == said

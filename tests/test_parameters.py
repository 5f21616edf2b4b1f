"""DEC parameters: defaults (docs/model.md §3), JSON format and validation, normalisation."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.dec.parameters import (
    PAPER_TABLE,
    DecParameters,
    ParameterArrays,
    default_parameters,
    denormalise,
    normalise,
)
from posture_id.errors import ParameterError


def test_default_body_gets_the_paper_table_exactly(tip):
    p = default_parameters(tip)
    for joint in ("ankle", "knee", "hip"):
        for key, value in PAPER_TABLE[joint].items():
            assert getattr(p[joint], key) == pytest.approx(value, rel=1e-12), (joint, key)
    np.testing.assert_allclose(p.array("kp"), [465.975, 245.25, 73.575], rtol=1e-12)
    assert [p[j].controls for j in ("ankle", "knee", "hip")] == ["com", "joint", "com"]


def test_defaults_scale_with_mgh_and_use_columns(winter, winter2, winter1):
    p3 = default_parameters(winter)
    np.testing.assert_allclose(p3.array("kp"), winter.mgh)
    assert p3["knee"].kd / p3["knee"].kp == pytest.approx(18.394 / 245.25)
    p2 = default_parameters(winter2)  # ankle and hip columns
    assert p2.joints == ("ankle", "hip")
    assert p2["hip"].kd / p2["hip"].kp == pytest.approx(18.394 / 73.575)
    assert p2["hip"].delay_s == 0.121 and p2["hip"].controls == "com"
    p1 = default_parameters(winter1)  # ankle column
    assert p1["ankle"].kd / p1["ankle"].kp == pytest.approx(116.49 / 465.975)
    assert p1["ankle"].delay_s == 0.100


def test_json_round_trip(tip, tmp_path):
    p = default_parameters(tip).replace("knee", kp=200.0, controls="com")
    path = tmp_path / "p.json"
    p.to_json(path)
    data = json.loads(path.read_text())
    assert set(data) == {"ankle", "knee", "hip"}
    assert data["knee"]["controls"] == "com" and data["knee"]["kp"] == 200.0
    assert DecParameters.from_json(path, tip) == p


def test_passive_terms_are_optional(tip):
    data = {j: {"kp": 1.0, "ki": 0.1, "kd": 0.5, "delay_s": 0.1, "controls": "joint"}
            for j in tip.joint_names}
    p = DecParameters.from_dict(data, tip)
    assert p["hip"].kpas == default_parameters(tip)["hip"].kpas


def _valid(tip):
    return default_parameters(tip).to_dict()


@pytest.mark.parametrize(
    "mutate, fragment",
    [
        (lambda d: d.pop("knee"), "module 'knee' is missing"),
        (lambda d: d["hip"].__setitem__("delay_s", -0.1), "field 'delay_s' is negative"),
        (lambda d: d.__setitem__("elbow", d["hip"]), "module 'elbow' is not a joint"),
        (lambda d: d["ankle"].__setitem__("controls", "trunk"), "field 'controls'"),
        (lambda d: d["ankle"].__setitem__("controls", ["com"]), "field 'controls' must be"),
        (lambda d: d["ankle"].pop("kd"), "field 'kd' is missing"),
        (lambda d: d["ankle"].__setitem__("kp", "high"), "field 'kp' must be a number"),
        (lambda d: d["ankle"].__setitem__("gain", 1), "unknown field 'gain'"),
        (lambda d: d["ankle"].__setitem__("ki", float("nan")), "field 'ki' is not finite"),
    ],
)
def test_bad_parameter_json_gets_a_clear_error(tip, tmp_path, mutate, fragment):
    data = _valid(tip)
    mutate(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ParameterError) as err:
        DecParameters.from_json(path, tip)
    assert fragment in str(err.value)
    assert str(path) in str(err.value)
    assert "\n" not in str(err.value)


def test_unreadable_json(tip, tmp_path):
    path = tmp_path / "x.json"
    path.write_text("{not json")
    with pytest.raises(ParameterError, match="not valid JSON"):
        DecParameters.from_json(path, tip)


def test_normalise_round_trip(tip):
    d = default_parameters(tip)
    p = d.replace("ankle", kp=d["ankle"].kp * 1.5, delay_s=0.05).replace("knee", controls="com")
    t = normalise(p, d)
    assert t.shape == (3, 5)
    np.testing.assert_allclose(t[0, :4], [0.5, 0.0, 0.0, -0.5])
    np.testing.assert_array_equal(t[:, 4], [1, 1, 1])
    back = denormalise(t, d)
    for j in tip.joint_names:
        for f in ("kp", "ki", "kd", "delay_s"):
            assert getattr(back[j], f) == pytest.approx(getattr(p[j], f))
        assert back[j].controls == p[j].controls


def test_parameter_arrays_validate_and_round_trip(tip):
    d = default_parameters(tip)
    arrays = ParameterArrays.from_parameters([d, d.replace("hip", kd=1.0)])
    assert arrays.n_trials == 2
    assert arrays.trial(1, tip.joint_names)["hip"].kd == 1.0
    with pytest.raises(ParameterError, match="'delay_s': trial 0, module 2 is negative"):
        bad = arrays.delay_s.copy()
        bad[0, 2] = -1
        ParameterArrays(**{**arrays.__dict__, "delay_s": bad})
    with pytest.raises(ParameterError, match="must lie in \\[-1, 1\\]"):
        ParameterArrays(**{**arrays.__dict__, "sign": np.full((2, 3), 1.5)})


def test_parameters_are_immutable(tip):
    p = default_parameters(tip)
    with pytest.raises(TypeError):
        p.modules["ankle"] = p.modules["knee"]
    assert hash(p) == hash(default_parameters(tip))

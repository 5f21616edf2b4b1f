"""How compare fits DEC: as identify does (the hybrid from the network's answer), and by
the locked fit from the body's defaults when that answer falls on the recording."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from posture_id.bodies.body import load_body
from posture_id.comparison.identified import IdentifiedFit
from posture_id.comparison.models import compare_models
from posture_id.dec.parameters import default_parameters
from posture_id.fitting.models import DecFit
from posture_id.identify.core import Identifier
from posture_id.simulation.batch import simulate
from posture_id.simulation.stimulus import prts
from posture_id.trials import prepare_trial

ONE_SEGMENT = "urdf/winter_1.75m_70kg_1seg.urdf"


@pytest.fixture(scope="module")
def setting():
    body = load_body(ONE_SEGMENT)
    stimulus = prts(cycles=2)
    recording = simulate(body, default_parameters(body), stimulus).to_recording()
    return body, prepare_trial(recording.with_sensor_noise(0.02, 4), stimulus)


@pytest.mark.slow("fits the DEC and IC models, 1 segment")
def test_compare_fits_dec_by_the_hybrid_where_a_network_serves_the_body(setting):
    body, trial = setting
    result = compare_models(trial, body, held_out=False)
    assert isinstance(result.fits["dec"], IdentifiedFit)
    assert result.to_dict()["dec"]["method"] == "hybrid"
    assert result.within_noise["dec"] and result.preferred == "dec"


@pytest.mark.slow("fits the DEC and IC models, 1 segment")
def test_a_hybrid_answer_that_falls_gives_way_to_the_locked_fit(setting, monkeypatch):
    body, trial = setting
    defaults = default_parameters(body)
    falling = defaults.replace(body.joint_names[0], kp=defaults.modules[
        body.joint_names[0]].kp / 20)
    monkeypatch.setattr(Identifier, "hybrid_fit", lambda self, trial, progress=None:
                        SimpleNamespace(parameters=falling, residual_sd=0.0))
    result = compare_models(trial, body, held_out=False)
    assert isinstance(result.fits["dec"], DecFit)  # the locked fit from the defaults
    assert not result.fits["dec"].falls and result.within_noise["dec"]
    assert "method" not in result.to_dict()["dec"]

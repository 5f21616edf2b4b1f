"""The check suite every identifier passes (in the manner of scikit-learn's
check_estimator): the paper's spectrogram CNN, the universal network, the hybrid and auto,
each on the shipped TIP example: its answer round-trips through JSON, another body's
recording is refused in one line, intervals are present, the verdict is typed, and the
same recording gives the same answer."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.bodies.body import load_body
from posture_id.errors import PostureIdError
from posture_id.fileio import json_text
from posture_id.identify import Identifier
from posture_id.identify.method import Method
from posture_id.learning.identifier import CnnIdentifier, NetworkIdentifier
from posture_id.learning.universal_identifier import UniversalIdentifier
from posture_id.models import DEC, TrustLevel
from posture_id.recording import Recording
from posture_id.simulation.batch import simulate
from posture_id.studies.demo import EXAMPLES_DIR

PAPER_CNN = "posture_id/learning/models/tip_default"
WINTER_2SEG = "posture_id/bodies/data/winter_1.75m_70kg_2seg.urdf"

IDENTIFIERS = {
    "paper CNN": (Method.CNN, PAPER_CNN),
    "universal network": (Method.CNN, None),
    "hybrid": (Method.HYBRID, None),
    "auto": (Method.AUTO, None),
}


@pytest.fixture(scope="module")
def body():
    return load_body()


@pytest.fixture(scope="module")
def recording(body):
    return Recording.from_csv(EXAMPLES_DIR / "tip_subject.csv", body.segment_names)


@pytest.fixture(scope="module", params=list(IDENTIFIERS), ids=list(IDENTIFIERS))
def identified(request, body, recording):
    method, model = IDENTIFIERS[request.param]
    identifier = Identifier(body, method, model)
    return identifier, identifier.identify(recording)


def test_both_networks_implement_one_identifier_protocol(body):
    other = load_body(WINTER_2SEG)
    for network in (CnnIdentifier.load(PAPER_CNN, body), UniversalIdentifier.bundled(body)):
        assert isinstance(network, NetworkIdentifier), type(network).__name__
        again = network.for_body(body)  # an instance method on both: the same network
        assert type(again) is type(network) and again.body is body
        assert network.for_body(other).body is other


@pytest.mark.slow("the example recording by four methods (module fixture)")
def test_check_the_answer_round_trips_through_json(identified, body):
    _, result = identified
    data = json.loads(json_text(result.to_dict()))
    assert DEC.parameters_from_dict(data["parameters"], body) == result.parameters
    assert data["method"] == result.method.value


@pytest.mark.slow("the example recording by four methods (module fixture)")
def test_check_intervals_present_and_verdict_typed(identified, body):
    _, result = identified
    assert result.intervals is not None
    assert result.intervals.lower.shape == (body.n_segments, 4)
    assert np.all(result.intervals.lower_si <= result.intervals.upper_si)
    assert isinstance(result.verdict.level, TrustLevel)
    assert json.loads(json_text(result.to_dict()))["trust"]["level"] in {t.value
                                                                        for t in TrustLevel}


@pytest.mark.slow("the example recording by four methods (module fixture)")
def test_check_the_same_recording_gives_the_same_answer(identified, recording):
    identifier, result = identified
    again = identifier.identify(recording)
    assert again.parameters == result.parameters
    assert again.verdict.level is result.verdict.level


@pytest.mark.slow("the example recording by four methods (module fixture)")
def test_check_another_bodys_recording_is_refused(identified):
    identifier, _ = identified
    other = load_body(WINTER_2SEG)
    with pytest.raises(PostureIdError, match="segment"):
        identifier.identify(simulate(other).to_recording())

"""``posture-id identify`` with the bundled models: classes recovered, the result is a
parameter file, and recordings a specialist CNN cannot judge are refused in one line
(the universal model, the default, reads them: tests/test_universal.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.bodies.body import TWO_SEGMENT_URDF as TWO_SEGMENT
from posture_id.bodies.body import load_body
from posture_id.cli import main
from posture_id.dec import default_parameters, sample_parameters
from posture_id.learning.bundled import bundled_model_dir
from posture_id.learning.identifier import CnnIdentifier
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate
from posture_id.trials import prepare_trial


def test_identify_recovers_the_classes_of_a_simulated_recording(tip, tmp_path, capsys):
    csv = tmp_path / "rec.csv"
    simulate(tip).to_csv(csv)  # the defaults: com, joint, com
    assert main(["identify", str(csv), "--out", str(tmp_path / "r.json")]) == 0
    result = json.loads((tmp_path / "r.json").read_text())
    assert [result["parameters"][j]["controls"] for j in tip.joint_names] == \
        ["com", "joint", "com"]
    assert result["cnn"]["model"]["layout"] == "universal" and result["method"] == "cnn"
    assert all(p > 0.9 for p in result["class_probability_com"].values()
               if p > 0.5)
    # the parameters object is a parameter file: simulate takes it back
    params = tmp_path / "p.json"
    params.write_text(json.dumps(result["parameters"]))
    assert main(["simulate", "--params", str(params), "--out", str(tmp_path / "b.csv")]) == 0


def test_identify_without_out_prints_the_result_and_writes_nothing(tip, tmp_path, capsys,
                                                                     monkeypatch):
    """``posture-id identify REC --body URDF``, the command outside checks run: the
    parameter table on stdout, a line on stderr that nothing was written, no file made;
    a cohort without --out is refused by name."""
    csv = tmp_path / "rec.csv"
    simulate(tip).to_csv(csv)
    monkeypatch.chdir(tmp_path)
    assert main(["identify", str(csv)]) == 0
    out, err = capsys.readouterr()
    assert "no --out: the result is printed, not written" in err
    rows = [line.split() for line in out.splitlines() if line.split()[:1] in
            (["ankle"], ["knee"], ["hip"])][:3]
    assert [r[5] for r in rows] == ["com", "joint", "com"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv"]
    assert main(["identify", str(tmp_path)]) == 2
    assert "a cohort's results need a folder: --out FOLDER" in capsys.readouterr().err


def test_identify_recovers_random_classes(tip):
    identifier = CnnIdentifier.bundled(tip)
    rng = np.random.default_rng(2024)
    checked = 0
    params = sample_parameters(tip, 12, rng)
    for b in range(12):
        truth = params.trial(b, tip.joint_names)
        trial = simulate(tip, truth)
        if not trial.stable:
            continue
        result = identifier.identify(prepare_trial(trial.to_recording()))
        assert result.classes == tuple(truth[j].controls for j in tip.joint_names), b
        checked += 1
    assert checked >= 6


def test_the_two_segment_body_has_its_own_model():
    body = load_body(TWO_SEGMENT)
    folder, notices = bundled_model_dir(body)
    assert folder.name == "winter_1.75m_70kg_2seg" and not notices
    result = CnnIdentifier.bundled(body).identify(prepare_trial(simulate(body).to_recording()))
    assert result.classes == ("com", "com")  # the defaults of a 2-segment body


@pytest.mark.parametrize(("change", "message"), [
    (lambda t: t.replace(amplitude=2.0), "the CNN was trained on PRTS 242 states ×2, 1° p-p"),
    (lambda t: t.replace(cycles=1), "the CNN was trained on 121 s"),
])
def test_recordings_of_another_stimulus_are_refused_by_a_specialist(tip, tmp_path, capsys,
                                                                    change, message):
    spec = change(_Stimulus())
    trial = simulate(tip, default_parameters(tip), prts(spec.amplitude, spec.cycles))
    csv = tmp_path / "other.csv"
    trial.to_csv(csv)
    specialist = str(bundled_model_dir(tip)[0])
    assert main(["identify", str(csv), "--network", specialist,
                 "--out", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "posture-id fit" in err
    assert str(csv) in err and not (tmp_path / "r.json").exists()
    # the default, the universal model, reads it and gets the defaults' classes
    assert main(["identify", str(csv), "--out", str(tmp_path / "u.json")]) == 0
    result = json.loads((tmp_path / "u.json").read_text())
    assert [result["parameters"][j]["controls"] for j in tip.joint_names] == \
        ["com", "joint", "com"]


def test_a_recording_of_other_segments_is_refused(tip, tmp_path, capsys):
    body = load_body(TWO_SEGMENT)
    csv = tmp_path / "two.csv"
    simulate(body).to_csv(csv)
    assert main(["identify", str(csv), "--out", str(tmp_path / "r.json")]) == 2
    assert "do not match the body's segments shank,thigh,trunk" in capsys.readouterr().err


def test_a_resampled_recording_gives_the_same_classes(tip):
    from posture_id.simulation import SimulationOptions

    fine = simulate(tip, options=SimulationOptions(sample_rate_hz=100.0))
    rec = Recording(fine.time, fine.tilt, fine.theta, fine.segments)
    result = CnnIdentifier.bundled(tip).identify(prepare_trial(rec))
    assert result.classes == ("com", "joint", "com")


class _Stimulus:
    def __init__(self, amplitude=1.0, cycles=2):
        self.amplitude, self.cycles = amplitude, cycles

    def replace(self, **kw):
        return _Stimulus(**{"amplitude": self.amplitude, "cycles": self.cycles, **kw})

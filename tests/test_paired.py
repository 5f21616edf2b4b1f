"""Paired (within-subject) comparisons (``posture-id norm compare --paired``): the
sign-flip test's level on pairs from one population, its power at the frequency that
changed, its exact p-values against hand enumeration, the refusals, and the command line
on FRF JSONs, tables, .mat files and identify results (docs/norms.md, "Paired
conditions")."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pytest

from posture_id.errors import PostureIdError
from posture_id.frf.bands import PETERKA_11
from posture_id.norms.groups import compare_groups
from posture_id.norms.norm import FrfSet
from posture_id.norms.paired import (
    compare_paired,
    compare_paired_parameters,
    sign_flip_test,
)
from posture_id.norms.parameters import IdentifiedGroup

F = np.asarray(PETERKA_11.centres_hz)
ROOT = Path(__file__).resolve().parents[1]


def _true_frfs(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, F) subjects' true FRFs: g·e^{−i2πfΔ}/(1 + i f/0.8), g and Δ varying."""
    g = 1 + 0.2 * rng.standard_normal(n)
    d = 0.15 * (1 + 0.2 * rng.standard_normal(n))
    return g[:, None] * np.exp(-2j * np.pi * F[None] * d[:, None]) / (1 + 1j * F[None] / 0.8)


def _measured(rng: np.random.Generator, h: np.ndarray, relative_sd) -> np.ndarray:
    """``h`` plus complex Gaussian noise whose SD is ``relative_sd`` (per subject, (n, 1),
    or one number) times the gain."""
    noise = rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)
    return h + np.asarray(relative_sd) * np.abs(h) * noise / np.sqrt(2)


def _pair(rng: np.random.Generator, n: int, change: float = 1.0, at: int = 2,
          relative_sd=0.15) -> tuple[FrfSet, FrfSet]:
    """n subjects measured in two conditions; condition B's gain × ``change`` at
    frequency ``at``."""
    h = _true_frfs(rng, n)
    hb = h.copy()
    hb[:, at] *= change
    names = tuple(f"s{i}" for i in range(n))
    return (FrfSet(F, _measured(rng, h, relative_sd)[:, :, None], ("COM",), names),
            FrfSet(F, _measured(rng, hb, relative_sd)[:, :, None], ("COM",), names))


def test_pairs_from_one_population_are_rejected_at_the_tests_level():
    """Both conditions from each subject's own true FRF plus independent noise (its size
    different from subject to subject): whole-FRF p < 0.05 in 3.0–7.2 % of 1000 data sets
    (± 3 binomial SDs around 5 %), by exact enumeration (10 pairs) and by random sign
    patterns (14 pairs); each frequency's p < 0.05 in 4.2–5.8 % of the 11 000 tests."""
    rng = np.random.default_rng(11)
    for n, permutations in ((10, 2000), (14, 499)):
        whole, per_frequency = [], []
        for _ in range(1000 if n == 10 else 500):
            sd = rng.uniform(0.05, 0.3, size=(n, 1))
            a, b = _pair(rng, n, relative_sd=sd)
            result = compare_paired(a, b, permutations=permutations, seed=int(rng.integers(1e9)))
            assert result.exact == (n == 10)
            whole.append(result.p_value < 0.05)
            per_frequency.extend(result.p_values.ravel() < 0.05)
        count = len(whole)
        half_width = 3 * np.sqrt(0.05 * 0.95 / count)
        assert abs(np.mean(whole) - 0.05) < half_width, (n, np.mean(whole))
        if n == 10:
            assert 0.042 < np.mean(per_frequency) < 0.058, np.mean(per_frequency)


def test_a_gain_change_at_one_frequency_is_found_there():
    """Condition B's gain 30 % higher at 0.3 Hz, 12 subjects, noise 15 % of the gain, 40
    data sets: p < 0.05 at 0.3 Hz in at least 38 (about 100 % expected), after max-T
    adjustment in at least 34 (96 %); the other frequencies below 0.05 in under 12 % of
    their tests (5 % expected); the gain ratio's 95 % interval holds 130 % in at least 34
    and excludes 100 % in at least 38."""
    rng = np.random.default_rng(3)
    found, adjusted, others, holds, excludes = [], [], [], [], []
    for _ in range(40):
        a, b = _pair(rng, 12, change=1.3, at=2)
        result = compare_paired(a, b, ("open", "closed"), permutations=2000)
        p = result.p_values[:, 0]
        found.append(p[2] < 0.05)
        adjusted.append(result.p_adjusted[2, 0] < 0.05)
        others.extend(np.delete(p, 2) < 0.05)
        holds.append(result.gain_ratio_low[2, 0] < 130 < result.gain_ratio_high[2, 0])
        excludes.append(result.gain_ratio_low[2, 0] > 100)
    assert sum(found) >= 38 and sum(adjusted) >= 34, (sum(found), sum(adjusted))
    assert np.mean(others) < 0.12, np.mean(others)
    assert sum(holds) >= 34 and sum(excludes) >= 38, (sum(holds), sum(excludes))
    assert 0.30 in result.differing(adjusted=True)["COM"]
    text = result.summary()
    assert "open against closed, 12 subjects in both (paired)" in text
    assert "0.3 Hz" in text.splitlines()[-1]


def test_exact_enumeration_gives_the_hand_computed_p_values():
    """n = 3, d = (3, 1, 1): the 8 patterns' sums ±5, ±3, ±3, ±1, so Q = 25/11 is reached
    by 2 of 8 (p = 0.25); d = (3, −1, 1): the observed sum 3 is reached or exceeded by 6
    (p = 0.75). Every difference the same complex number up to a positive factor: only the
    pattern and its negation reach it, p = 2/2ⁿ, at each frequency and for the whole FRF.
    And against a brute-force loop over the 2⁷ patterns for complex data: every p-value,
    max-T adjusted ones and the whole FRF's."""
    assert sign_flip_test(np.array([3.0, 1.0, 1.0]), 8).p_values[0] == 0.25
    assert sign_flip_test(np.array([3.0, -1.0, 1.0]), 8).p_values[0] == 0.75
    n = 6
    c = np.arange(1, n + 1, dtype=float)
    h = np.exp(-2j * np.pi * F * 0.15)
    a = FrfSet(F, (h[None] * (1 + 0.1 * c[:, None]))[:, :, None], ("COM",),
               tuple(map(str, c)))
    b = FrfSet(F, np.broadcast_to(h, (n, len(F)))[:, :, None], ("COM",), tuple(map(str, c)))
    result = compare_paired(a, b, permutations=64)
    assert result.exact and result.patterns == 64
    np.testing.assert_allclose(result.p_values, 2 / 64, rtol=1e-12)
    assert result.p_value == pytest.approx(2 / 64, rel=1e-12)
    np.testing.assert_allclose(result.gain_ratio_percent[:, 0], 100 / np.exp(
        np.mean(np.log(1 + 0.1 * c))), rtol=1e-12)
    np.testing.assert_allclose(result.phase_difference_deg, 0, atol=1e-9)

    rng = np.random.default_rng(0)
    d = rng.standard_normal((7, 5)) + 1j * rng.standard_normal((7, 5)) + 0.4
    test = sign_flip_test(d, 200)
    q_of = [np.abs(np.array(s) @ d) ** 2 / np.sum(np.abs(d) ** 2, axis=0)
            for s in itertools.product((1.0, -1.0), repeat=7)]
    observed = np.abs(d.sum(axis=0)) ** 2 / np.sum(np.abs(d) ** 2, axis=0)
    np.testing.assert_allclose(test.statistic, observed, rtol=1e-12)
    np.testing.assert_allclose(test.p_values, np.mean(
        [q >= observed - 1e-9 for q in q_of], axis=0), rtol=1e-12)
    np.testing.assert_allclose(test.p_adjusted, np.mean(
        [q.max() >= observed - 1e-9 for q in q_of], axis=0), rtol=1e-12)
    assert test.global_p == pytest.approx(np.mean(
        [q.sum() >= observed.sum() - 1e-9 for q in q_of]), rel=1e-12)
    assert test.exact and test.patterns == 128


def test_random_sign_patterns_count_the_observed_one():
    """2ⁿ above the permutations: N random patterns, p = (1 + #)/(1 + N) ≥ 1/(1 + N);
    the same seed, the same p-values."""
    d = np.ones((12, 3)) * (1 + 1j)
    test = sign_flip_test(d, 99, seed=4)
    assert not test.exact and test.patterns == 99
    np.testing.assert_allclose(test.p_values, 1 / 100)
    assert test.global_p == pytest.approx(1 / 100)
    rng = np.random.default_rng(2)
    noisy = rng.standard_normal((15, 4))
    first, again = sign_flip_test(noisy, 500, seed=7), sign_flip_test(noisy, 500, seed=7)
    np.testing.assert_array_equal(first.p_values, again.p_values)
    assert np.all(first.p_adjusted >= first.p_values)
    zero = sign_flip_test(np.zeros((5, 2)), 100)
    np.testing.assert_array_equal(zero.p_values, 1.0)


def _group(values: dict[str, list[float]], names) -> IdentifiedGroup:
    return IdentifiedGroup({k: np.asarray(v, float) for k, v in values.items()},
                           {k: np.full(len(v), 0.01) for k, v in values.items()}, tuple(names))


def test_paired_parameters_use_the_same_sign_flips():
    """Identified parameters: the differences A − B (3, −1, 1) give p = 0.75 exactly, as the
    FRF test does on the same numbers; a delay 20 ms longer in B for every subject gives
    the smallest p, 2/2ⁿ; the mean difference's t interval by hand."""
    from scipy.stats import t

    a = _group({"ankle kp": [10, 11, 12], "ankle delay_s": [0.1, 0.12, 0.11]}, "abc")
    b = _group({"ankle kp": [7, 12, 11], "ankle delay_s": [0.12, 0.14, 0.13]}, "ABC")
    result = compare_paired_parameters(a, b, permutations=100)
    rows = {r["parameter"]: r for r in result.rows}
    assert rows["ankle kp"]["p_value"] == 0.75
    assert rows["ankle delay_s"]["p_value"] == pytest.approx(2 / 8)
    d = np.array([3.0, -1.0, 1.0])
    half = t.ppf(0.975, 2) * d.std(ddof=1) / np.sqrt(3)
    assert rows["ankle kp"]["low"] == pytest.approx(d.mean() - half)
    assert rows["ankle kp"]["high"] == pytest.approx(d.mean() + half)
    assert result.exact and result.patterns == 8
    assert result.pairs == (("a", "A"), ("b", "B"), ("c", "C"))
    json.dumps(result.to_dict(), allow_nan=False)
    assert "differ at 5 %" in result.summary()


def test_what_cannot_be_paired_is_refused():
    """Unequal groups (both counts named), fewer than 2 pairs, other frequencies, other
    channels, a level out of range; the same for identified parameters."""
    rng = np.random.default_rng(1)
    a, b = _pair(rng, 6)
    five = FrfSet(F, b.response[:5], b.channels, b.names[:5])
    with pytest.raises(PostureIdError, match="open has 6, closed has 5"):
        compare_paired(a, five, ("open", "closed"))
    one = FrfSet(F, a.response[:1], a.channels, a.names[:1])
    with pytest.raises(PostureIdError, match="at least 2 subjects"):
        compare_paired(one, one)
    shifted = FrfSet(F * 1.1, b.response, b.channels, b.names)
    with pytest.raises(PostureIdError, match="different frequencies"):
        compare_paired(a, shifted)
    renamed = FrfSet(F, b.response, ("COM_x",), b.names)
    with pytest.raises(PostureIdError, match="channels differ"):
        compare_paired(a, renamed)
    with pytest.raises(PostureIdError, match="level"):
        compare_paired(a, b, level=95)
    pa = _group({"ankle kp": [1, 2, 3]}, "abc")
    with pytest.raises(PostureIdError, match="A has 3, B has 2"):
        compare_paired_parameters(pa, _group({"ankle kp": [1, 2]}, "ab"))
    with pytest.raises(PostureIdError, match="other joints"):
        compare_paired_parameters(pa, _group({"hip kp": [1, 2, 3]}, "abc"))
    with pytest.raises(PostureIdError, match="at least 2 subjects"):
        compare_paired_parameters(_group({"ankle kp": [1]}, "a"),
                                  _group({"ankle kp": [2]}, "b"))


def _frf_files(folder: Path, frfs: FrfSet, prefix: str) -> list[Path]:
    """One FRF JSON per subject, written by :class:`FrequencyResponse` (as ``posture-id
    frf --band-preset peterka11`` writes them)."""
    from posture_id.frf.response import FrequencyResponse, FrfOptions

    folder.mkdir(exist_ok=True)
    paths = []
    for k, name in enumerate(frfs.names):
        frf = FrequencyResponse(F, frfs.response[k], None, ("body COM",), 6, 20.0,
                                np.full(1, np.nan), FrfOptions.lab_convention(PETERKA_11),
                                f"{prefix}{name}")
        paths.append(folder / f"{prefix}{name}.frf.json")
        frf.to_json(paths[-1])
    return paths


def test_the_command_line_compares_paired_frf_files_tables_and_mats(tmp_path, capsys):
    """--paired on FRF JSONs, on two CSV tables and on two .mat files gives one answer (the
    API's); unequal groups, a copied file and a file in both groups are refused in one
    line (exit status 2)."""
    from scipy.io import savemat

    from posture_id.cli import main

    a, b = _pair(np.random.default_rng(9), 8, change=1.35, at=2)
    open_files = _frf_files(tmp_path / "open", a, "open_")
    closed_files = _frf_files(tmp_path / "closed", b, "closed_")
    out, plot = tmp_path / "paired.json", tmp_path / "paired.png"
    assert main(["norm", "compare", "--paired", "--group", *map(str, open_files), "--group",
                 *map(str, closed_files), "--names", "open", "closed", "--out", str(out),
                 "--plot", str(plot)]) == 0
    printed = capsys.readouterr().out
    assert "open against closed, 8 subjects in both (paired)" in printed
    answer = json.loads(out.read_text())
    assert plot.stat().st_size > 0
    expected = compare_paired(FrfSet(F, a.response, ("body COM",), a.names),
                              FrfSet(F, b.response, ("body COM",), b.names), ("open", "closed"))
    assert answer["paired"] is True and answer["pairs"] == 8 and answer["exact"] is True
    assert answer["p_value"] == pytest.approx(expected.p_value, rel=1e-12)
    assert answer["subjects"][0] == ["open_s0.frf", "closed_s0.frf"]
    rows = answer["per_frequency"]["body COM"]
    assert [r["p_value"] for r in rows] == pytest.approx(expected.p_values[:, 0].tolist())
    assert rows[2]["p_value"] < 0.05 and answer["differ_at_5_percent_hz"]["body COM"]

    tables = []
    for name, frfs in (("open", a), ("closed", b)):
        table = tmp_path / f"{name}.csv"
        cells = [",".join(f"{float(h.real)!r},{float(h.imag)!r}" for h in frfs.response[i, :, 0])
                 for i in range(len(frfs))]
        table.write_text("subject," + ",".join(f"{f:g}_re,{f:g}_im" for f in F) + "\n"
                         + "".join(f"s{i},{c}\n" for i, c in enumerate(cells)))
        tables.append(table)
        savemat(tmp_path / f"{name}.mat", {"H": frfs.response[:, :, 0]})
    mats = [str(tmp_path / "open.mat"), str(tmp_path / "closed.mat")]
    for k, (first, second, extra) in enumerate((
            (str(tables[0]), str(tables[1]), []),
            (mats[0], mats[1], ["--variable", "H", "--frequencies", *map(str, F)]))):
        other = tmp_path / f"other{k}.json"
        assert main(["norm", "compare", "--paired", "--group", first, "--group", second,
                     "--out", str(other), *extra]) == 0
        again = json.loads(other.read_text())
        assert again["p_value"] == pytest.approx(answer["p_value"], rel=1e-9)
        assert [r["p_value"] for r in again["per_frequency"]["COM"]] == pytest.approx(
            [r["p_value"] for r in rows], rel=1e-9)
    capsys.readouterr()

    copied = tmp_path / "closed" / "copied.frf.json"
    copied.write_bytes(open_files[3].read_bytes())
    for argv, named in (
            ([*map(str, open_files), "--group", *map(str, closed_files[:-1])],
             "open has 8 subjects, closed has 7"),
            ([*map(str, open_files), "--group", *map(str, closed_files[:3]), str(copied),
              *map(str, closed_files[4:])], "same FRF as its pair"),
            ([*map(str, open_files), "--group", *map(str, closed_files[:7]),
              str(open_files[0])], "in both groups")):
        target = tmp_path / "refused.json"
        assert main(["norm", "compare", "--paired", "--names", "open", "closed", "--group",
                     *argv, "--out", str(target)]) == 2, named
        err = capsys.readouterr().err.strip()
        assert named in err and len(err.splitlines()) == 1, err
        assert not target.exists()


def test_without_paired_nothing_changes(tmp_path, capsys):
    """The same files without --paired: the unpaired comparison, as compare_groups gives it
    (no paired field), and groups of unequal sizes still compared."""
    from posture_id.cli import main

    a, b = _pair(np.random.default_rng(9), 8)
    open_files = _frf_files(tmp_path / "open", a, "open_")
    closed_files = _frf_files(tmp_path / "closed", b, "closed_")
    out = tmp_path / "groups.json"
    assert main(["norm", "compare", "--group", *map(str, open_files), "--group",
                 *map(str, closed_files[:6]), "--permutations", "99", "--bootstrap", "50",
                 "--out", str(out)]) == 0
    answer = json.loads(out.read_text())
    expected = compare_groups(FrfSet(F, a.response, ("body COM",), a.names),
                              FrfSet(F, b.response[:6], ("body COM",), b.names[:6]),
                              permutations=99, bootstrap=50).to_dict()
    assert "paired" not in answer and answer["sizes"] == [8, 6]
    for key in ("p_value", "statistic", "leaves_zero_s", "pir"):
        assert answer[key] == expected[key], key
    assert "permutation test of the distance between the group means" in capsys.readouterr().out


@pytest.fixture(scope="module")
def identified(tmp_path_factory) -> Path:
    """An identify result of the shipped TIP example (the network), the template of the
    subjects' results."""
    from posture_id.cli import main

    path = tmp_path_factory.mktemp("identified") / "tip.json"
    assert main(["identify", str(ROOT / "posture_id" / "studies" / "examples" /
                                 "tip_subject.csv"), "--method", "cnn", "--out",
                 str(path)]) in (0, 1)
    return path


def _result_like(template: dict, path: Path, scale: dict[str, float]) -> Path:
    """The template's result with each field's value (and interval) times ``scale``."""
    data = json.loads(json.dumps(template))
    for joint, module in data["parameters"].items():
        for field, factor in scale.items():
            module[field] *= factor
            box = data["intervals"]["modules"][joint][field]
            box["lower_si"] *= factor
            box["upper_si"] *= factor
    path.write_text(json.dumps(data))
    return path


def test_the_command_line_compares_paired_identify_results(identified, tmp_path, capsys):
    """Six subjects identified in two conditions (results made from one identify result,
    every subject's delays 25 % longer in B, Kp up or down by subject): every delay's p is
    the smallest, 2/2⁶; Kp does not differ; the unpaired comparison of the same files
    still runs; a copied result is refused."""
    from posture_id.cli import main

    template = json.loads(identified.read_text())
    rng = np.random.default_rng(5)
    first, second = [], []
    for i in range(6):
        base = {"kp": 1 + 0.1 * rng.standard_normal(), "delay_s": 1 + 0.1 * rng.standard_normal(),
                "kd": 1.0, "ki": 1.0}
        change = {"kp": base["kp"] * (1 + 0.05 * (-1) ** i),
                  "delay_s": base["delay_s"] * 1.25, "kd": 1.0, "ki": 1.0}
        first.append(str(_result_like(template, tmp_path / f"a{i}.json", base)))
        second.append(str(_result_like(template, tmp_path / f"b{i}.json", change)))
    out = tmp_path / "paired.json"
    assert main(["norm", "compare", "--paired", "--group", *first, "--group", *second,
                 "--names", "rested", "tired", "--out", str(out), "--plot",
                 str(tmp_path / "p.png")]) == 0
    answer = json.loads(out.read_text())
    rows = {r["parameter"]: r for r in answer["parameters"]}
    assert answer["paired"] is True and answer["exact"] is True and answer["pairs"] == 6
    for joint in template["parameters"]:
        assert rows[f"{joint} delay_s"]["p_value"] == pytest.approx(2 / 64)
        assert rows[f"{joint} delay_s"]["high"] < 0  # A − B: B's delays longer
        assert rows[f"{joint} kp"]["p_value"] > 0.2
    assert "rested against tired, 6 subjects in both (paired)" in capsys.readouterr().out
    unpaired = tmp_path / "unpaired.json"
    assert main(["norm", "compare", "--group", *first, "--group", *second[:5],
                 "--permutations", "99", "--bootstrap", "20", "--out", str(unpaired)]) == 0
    assert "paired" not in json.loads(unpaired.read_text())
    capsys.readouterr()
    copy = tmp_path / "copy.json"
    copy.write_text(Path(first[2]).read_text())
    assert main(["norm", "compare", "--paired", "--group", *first, "--group", *second[:2],
                 str(copy), *second[3:], "--out", str(tmp_path / "x.json")]) == 2
    err = capsys.readouterr().err
    assert "same identified parameters as its pair" in err and len(err.strip().splitlines()) == 1
    assert main(["norm", "compare", "--paired", "--group", *first, "--group", *second[:4],
                 "--out", str(tmp_path / "x.json")]) == 2
    assert "A has 6 subjects, B has 4" in capsys.readouterr().err

"""Why the design's check reads as it does: is the locked fit linear where the design
says a parameter is determined, and does motor noise bias the locked response?

Run:  .venv/bin/python benchmarks/design_linearity.py [--draws 300] [--fits 2]

On the 2-segment Winter body, for 3 subjects drawn from docs/model.md §5's prior (seed 5) and the
242-state PRTS ×2 and the 80-state PRTS ×6 at 1°:

1. *scatter*: the linearised estimate A⁻¹J̄ᵀz of ``--draws`` white sensor-noise draws
   (0.05°), projected as the locked fit projects the sway, against the standard error
   the design predicts for the same subject (:func:`~posture_id.design.predict.
   predict_protocols`'s ingredients): the ratio predicted / realised SD per parameter;
2. *fit*: for ``--fits`` noisy recordings of each subject under the 80-state PRTS, the
   locked least-squares fit (from the truth, classes known) against the linearised
   estimate of the same noise, weighted by the fit's own weights: their largest
   difference on the parameters the design calls determined;
3. *dithering*: for 6 subjects with motor noise leaving 30 % of the body COM sway locked,
   48 cycles of the noise-driven sway (noisy − clean): at the excited harmonics, the
   power of its mean over the cycles against the mean's own noise (≈ 1 when there is no
   bias, ≫ 1 when motor noise shifts the locked response).

Prints its numbers (docs/design.md, "Do the predictions hold?").
"""

from __future__ import annotations

import argparse

import numpy as np

from posture_id.bodies.body import load_body
from posture_id.dec.parameters import default_parameters, normalise_arrays
from posture_id.dec.prior import sample_parameters
from posture_id.design.information import harmonic_information
from posture_id.design.predict import DesignOptions, _Recording, prior_width
from posture_id.design.report import UNDETERMINED
from posture_id.fitting import FitOptions, fit_recording
from posture_id.fitting.options import FixedClasses
from posture_id.fitting.unknowns import q_from_targets
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.simulation.batch import simulate, simulate_batch
from posture_id.simulation.noise import DEFAULT_CUTOFF_HZ, MotorNoise
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.protocols import PrtsProtocol
from posture_id.simulation.subjects import UNIT_LEVEL_PER_DEG, motor_levels_for_share
from posture_id.trials import prepare_trial

BODY = "urdf/winter_1.75m_70kg_2seg.urdf"
SENSOR_DEG = 0.05


def _linearised(jac: np.ndarray, z: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(P,) the weighted least-squares step A⁻¹J̄ᵀW̄z of harmonics ``z`` (K, M)."""
    jw, zw = jac * weights[:, :, None], z * weights
    jr = np.concatenate([jw.real, jw.imag], axis=1)
    zr = np.concatenate([zw.real, zw.imag], axis=1)
    return np.linalg.solve(np.einsum("kip,kiq->pq", jr, jr), np.einsum("kip,ki->p", jr, zr))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=300)
    parser.add_argument("--fits", type=int, default=2)
    args = parser.parse_args()
    body = load_body(BODY)
    n = body.n_segments
    options = DesignOptions()
    sim = SimulationOptions(dt=options.dt)
    params = sample_parameters(body, 3, np.random.default_rng(5))
    targets = normalise_arrays(params, default_parameters(body))
    rng = np.random.default_rng(1)
    width0 = prior_width()
    for protocol in (PrtsProtocol(242, 0.25, 1.0, 2), PrtsProtocol(80, 0.25, 1.0, 6)):
        rec = _Recording(body, protocol, options, lambda message: None)
        period, cycles = rec.projection.period, rec.projection.cycles
        for d in range(len(targets)):
            jac = rec.harmonics_jacobian(q_from_targets(targets[d]), list(range(4 * n)))
            noise = np.broadcast_to((SENSOR_DEG**2 / period / cycles) * np.eye(n),
                                    (jac.shape[0], n, n))
            se = np.sqrt(np.diag(harmonic_information(jac, noise).fit_covariance()))
            ones = np.ones(jac.shape[:2])
            steps = [_linearised(jac, rec.projection.spectrum(
                SENSOR_DEG * rng.standard_normal((rec.n_samples, n))), ones)
                for _ in range(args.draws)]
            ratio = se / np.std(steps, axis=0)
            print(f"scatter, {protocol.label()}, subject {d}: predicted / realised SD "
                  f"{ratio.min():.2f}–{ratio.max():.2f}", flush=True)
            if protocol.states != 80:
                continue
            determined = 2 * 1.645 * se / width0 < UNDETERMINED
            trial_params = params.trial(d, body.joint_names)
            clean = simulate(body, trial_params, rec.profile, sim)
            for seed in range(args.fits):
                recording = clean.to_recording().with_sensor_noise(SENSOR_DEG, 100 + seed)
                trial = prepare_trial(recording, rec.profile)
                weights = 1.0 / LockedProjection.for_trial(trial).noise
                z = rec.projection.spectrum(np.degrees(recording.theta - clean.theta))
                step = _linearised(jac, z, weights)
                fit = fit_recording(trial, body, init=trial_params, options=FitOptions(
                    simulation=sim, locked=LockedOptions(), classes=FixedClasses(),
                    warm_start=False, threads=1))
                moved = (fit.normalised[:, :4] - targets[d][:, :4]).T.reshape(-1)
                gap = np.abs(moved - step)[determined]
                print(f"fit, subject {d}, noise {seed}: |fit − linearised| on the "
                      f"{determined.sum()} determined parameters ≤ {gap.max():.3f}",
                      flush=True)
    _dithering(body, sim)


def _dithering(body, sim: SimulationOptions, subjects: int = 6, cycles: int = 48) -> None:
    params = sample_parameters(body, subjects, np.random.default_rng(11))
    seeds = np.arange(subjects) + 7
    rate = sim.sample_rate_hz
    for protocol in (PrtsProtocol(80, 0.25, 1.0, 6), PrtsProtocol(242, 0.25, 1.0, 2)):
        found = motor_levels_for_share(body, params, protocol.profile(),
                                       np.full(subjects, 0.3), seeds,
                                       UNIT_LEVEL_PER_DEG * protocol.peak_to_peak_deg,
                                       DEFAULT_CUTOFF_HZ, sim)
        long = protocol.with_cycles(cycles + 1).profile()
        clean = simulate_batch(body, params, long, sim, workers=2)
        noisy = simulate_batch(body, params, long, sim, workers=2, motor_noise=[
            MotorNoise(float(v), DEFAULT_CUTOFF_HZ, int(s))
            for v, s in zip(np.nan_to_num(found.level), seeds, strict=True)])
        period = int(round(protocol.period_s * rate))
        x = np.degrees(noisy.theta - clean.theta)[:, period:(cycles + 1) * period]
        spec = np.fft.rfft(x.reshape(subjects, cycles, period, -1), axis=2)
        spec = spec[:, :, 1:period // 2 + 1] / period
        tilt = np.abs(np.fft.rfft(long.angle(np.arange(period) / rate))[1:period // 2 + 1])
        excited = (tilt > 1e-3 * tilt.max()) & (np.arange(1, period // 2 + 1) * rate / period
                                                 <= 2.0)
        ok = clean.stable & noisy.stable & found.usable
        bias = np.abs(spec.mean(axis=1)) ** 2 / (spec.var(axis=1) / cycles)  # (S, H, N)
        ratio = np.median(bias[ok][:, excited], axis=1)  # (S', N)
        print(f"dithering, {protocol.label()}: |mean|² / its own noise at the excited "
              f"harmonics, median per subject and channel {ratio.min():.2f}–{ratio.max():.2f}"
              f" ({ok.sum()} subjects)", flush=True)


if __name__ == "__main__":
    main()

"""Compiler flags for the fit's CasADi model: how long gcc takes, how fast the code runs.

Run:  .venv/bin/python benchmarks/compile_flags.py [--segments 3] [--samples 6051]

Generates the C code of the fit's compiled model (one block's simulation and its
directional derivatives, ``posture_id.fitting.problem.CompiledModel``) for the TIP (or a
Winter body of ``--segments``), compiles it with -O1, -Og and -O0 (with ``-fPIC -shared
-march=native``), and times in one run: the compile, and on a recording of ``--samples``
one simulation and one Jacobian chunk (the columns one thread evaluates, carried through
the blocks), medians of three.
Writes docs/results/compile_flags.json.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FLAG_SETS = (["-O1"], ["-Og"], ["-O0"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--segments", type=int, default=3)
    parser.add_argument("--samples", type=int, default=6051)
    args = parser.parse_args(argv)
    from posture_id import load_body
    from posture_id.dec.parameters import default_parameters
    from posture_id.fileio import atomic_write_text
    from posture_id.fitting import problem as problem_module
    from posture_id.fitting.build import Backend
    from posture_id.fitting.options import FitOptions
    from posture_id.fitting.symbolic import body_constants, step_inputs
    from posture_id.fitting.unknowns import q_from_targets
    from posture_id.simulation import prts

    urdf = (ROOT / "urdf" / "tip_default.urdf" if args.segments == 3
            else ROOT / "urdf" / f"winter_1.75m_70kg_{args.segments}seg.urdf")
    body = load_body(urdf)
    key = problem_module.ProblemKey.of(body, args.samples, FitOptions())
    delays = default_parameters(body).array("delay_s") / key.compiled.dt
    captured = {}

    def keep(name, code_key, build, notify=None, mode=None):  # the functions, uncompiled
        captured["functions"] = build()
        return captured["functions"], Backend(False, reason="benchmark")

    real = problem_module.compile_functions
    problem_module.compile_functions = keep
    try:
        model = problem_module.CompiledModel(key.model_key(delays))
    finally:
        problem_module.compile_functions = real
    functions = captured["functions"]
    n = body.n_segments
    blocks = -(-(args.samples - 1) // problem_module.BLOCK_SAMPLES)
    n_steps_u = blocks * model.block_steps
    tilt, velocity = prts().on_grid(key.compiled.dt, n_steps_u)
    u = step_inputs(tilt, velocity, n_steps_u)
    classes = np.zeros((n, 5))
    classes[:, 4] = default_parameters(body).array("sign")
    q = q_from_targets(classes, np.zeros((n, 2)))
    context = np.concatenate([body_constants(body)] + [default_parameters(body).array(f)
                                                       for f in problem_module._SCALED_FIELDS])
    chunk = list(range(model.width))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        generator = ca.CodeGenerator("model.c")
        for f in functions:
            generator.add(f)
        generator.generate(tmp + os.sep)
        source = Path(tmp) / "model.c"
        for flags in FLAG_SETS:
            library = Path(tmp) / f"model{flags[0]}.so"
            start = time.perf_counter()
            subprocess.run(["gcc", *flags, "-fPIC", "-shared", "-march=native", str(source),
                            "-o", str(library), "-lm"], check=True)
            compile_s = time.perf_counter() - start
            model.sim = ca.external(functions[0].name(), str(library))
            model.dirs = ca.external(functions[1].name(), str(library))
            sim_s, jac_s = [], []
            for _ in range(3):
                start = time.perf_counter()
                _, starts = model.rollout(q, u, context)
                sim_s.append(time.perf_counter() - start)
                start = time.perf_counter()
                model.directions(q, u, context, starts, chunk)
                jac_s.append(time.perf_counter() - start)
            rows.append({"flags": " ".join(flags), "compile_s": round(compile_s, 2),
                         "simulation_s": round(float(np.median(sim_s)), 4),
                         "jacobian_chunk_s": round(float(np.median(jac_s)), 4)})
            print(f"{' '.join(flags):4s}: compile {compile_s:6.1f} s, simulation "
                  f"{rows[-1]['simulation_s']:.3f} s, Jacobian chunk "
                  f"{rows[-1]['jacobian_chunk_s']:.3f} s", flush=True)
        size = source.stat().st_size
    out = ROOT / "docs" / "results" / "compile_flags.json"
    atomic_write_text(out, json.dumps({"segments": n, "samples": args.samples,
                                       "source_bytes": size, "rows": rows}, indent=2))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

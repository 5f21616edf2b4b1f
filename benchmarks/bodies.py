"""Markdown table of the preset bodies' m·g·h and default DEC gains, next to the paper's.

Run:  .venv/bin/python benchmarks/bodies.py      (the table in docs/bodies.md)
"""

from __future__ import annotations

from pathlib import Path

from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.dec.parameters import default_parameters

URDF = Path(__file__).resolve().parents[1] / "urdf"
BODIES = [
    ("paper TIP (default)", DEFAULT_URDF),
    ("Winter 1.80 m 80 kg", None),
    ("TALOS (half-sitting)", URDF / "talos_tip.urdf"),
    ("Unitree G1", URDF / "g1_tip.urdf"),
    ("human model", URDF / "human_tip.urdf"),
]


def main() -> None:
    import tempfile

    from posture_id.bodies.anthropometry import straight_links, winter_segments
    from posture_id.bodies.urdf_writer import write_chain_urdf

    print("| body | mass kg | module | m·g·h N·m/rad | Kp | Ki | Kd | Δ s | Kpas | Bpas | class |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for label, path in BODIES:
            if path is None:
                path = write_chain_urdf(Path(tmp) / "winter.urdf", "winter",
                                        straight_links(winter_segments(1.80, 80.0, 3)))
            body = load_body(path)
            params = default_parameters(body)
            for i, (joint, mgh) in enumerate(zip(body.joint_names, body.mgh, strict=True)):
                m = params[joint]
                head = f"| {label} | {body.total_mass:.1f} " if i == 0 else "| | "
                print(f"{head}| {joint} | {mgh:.2f} | {m.kp:.2f} | {m.ki:.3f} | {m.kd:.3f} | "
                      f"{m.delay_s:.3f} | {m.kpas:.2f} | {m.bpas:.2f} | {m.controls} |")


if __name__ == "__main__":
    main()

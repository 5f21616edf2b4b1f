"""docs/images/architecture.png: the package's layers (read from pyproject.toml's layer
contract, the one import-linter checks) and the model protocol between them.

Run:  .venv/bin/python docs/config/architecture_figure.py [--out docs/images/architecture.png]
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: What each layer's packages do, in a few words (the picture's second line).
ROLES = {
    "cli": "the command line",
    "studies": "benchmarks, calibration runs, the demo",
    "comparison": "two models on one recording or a cohort",
    "norms": "normative FRF sets, tests against them",
    "identify": "networks + least squares + the verdict",
    "design": "which protocol identifies best",
    "learning": "the networks (torch)",
    "fitting": "least squares (CasADi), the frequency-domain fit",
    "datasets": "training sets",
    "frf": "cycle averages, FRFs, locked harmonics",
    "models": "DEC, IC (and new ones) behind one protocol",
    "trials": "a recording and its stimulus, checked",
    "simulation": "the compiled simulator, stimuli",
    "uncertainty": "intervals, calibration",
    "motion_capture": "C3D, markers to angles",
    "force_plate": "the COP to the body's sway",
    "manifest": "a whole study from its manifest",
    "robots": "MuJoCo beside the simulator",
    "text_table": "a lab's numeric text files, read as they are",
    "dec": "DEC's parameters and prior",
    "bodies": "URDF bodies (Pinocchio)",
    "cohorts": "the cohort runner: journal, summary.csv",
    "fileio": "atomic writes, JSON, results",
}


def layers() -> list[list[str]]:
    """The layer contract's layers, top first, each a list of package names (read from
    pyproject.toml's ``type = "layers"`` contract)."""
    text = (ROOT / "pyproject.toml").read_text()
    block = re.search(r'type = "layers"\s*\nlayers = \[(.*?)\n\]', text, re.S)
    if block is None:
        raise SystemExit("pyproject.toml: no layers contract found")
    return [[p.strip().removeprefix("posture_id.") for p in layer.split("|")]
            for layer in re.findall(r'"([^"]+)"', block.group(1))]


def draw(out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

    rows = layers()
    height = 0.62 * len(rows) + 1.0
    fig, ax = plt.subplots(figsize=(11.5, height))
    ax.set_xlim(0, 11.5)
    ax.set_ylim(0, height)
    ax.axis("off")
    top = height - 0.55
    model_row = None
    for i, packages in enumerate(rows):
        y = top - 0.62 * i
        width = 7.2 / len(packages)
        for j, name in enumerate(packages):
            x = 0.2 + j * width
            colour = "#c7d7f5" if name == "models" else "#eef1f6"
            ax.add_patch(FancyBboxPatch((x + 0.04, y - 0.25), width - 0.08, 0.5,
                                        boxstyle="round,pad=0.02", fc=colour, ec="#4a5a7a",
                                        lw=0.8))
            role = ROLES.get(name, "")
            ax.text(x + width / 2, y + 0.07, name, ha="center", va="center", fontsize=9,
                    weight="bold")
            if role:
                ax.text(x + width / 2, y - 0.12, role, ha="center", va="center", fontsize=6.5,
                        color="#333")
            if name == "models":
                model_row = y
    ax.annotate("", xy=(0.1, 0.2), xytext=(0.1, top + 0.2),
                arrowprops={"arrowstyle": "->", "color": "#888"})
    ax.text(0.02, height / 2, "imports only downward", rotation=90, va="center", fontsize=7,
            color="#666")
    # the protocol, beside its layer
    px, pw = 7.9, 3.4
    py = model_row if model_row is not None else height / 2
    lines = ["Model protocol", "name, label, capabilities", "parameters (JSON, \"model\" key)",
             "default parameters, bounds", "simulate(body, params, stimulus)",
             "com_sway_deg(params, body, trial)",
             "FrequencyModel: closed_loop(s), is_stable", "",
             "DEC: LOCKED_FIT, NETWORK, DESIGN", "IC: FREQUENCY_RESPONSE, DESIGN",
             "a new model: implement, register()"]
    box_h = 0.24 * len(lines) + 0.2
    ax.add_patch(FancyBboxPatch((px, py - box_h / 2), pw, box_h, boxstyle="round,pad=0.03",
                                fc="#c7d7f5", ec="#4a5a7a", lw=1.0))
    for k, text in enumerate(lines):
        ax.text(px + 0.15, py + box_h / 2 - 0.25 - 0.24 * k, text, fontsize=7.5,
                weight="bold" if k == 0 else "normal", va="center")
    ax.add_patch(FancyArrowPatch((7.45, py), (px - 0.02, py), arrowstyle="-", color="#4a5a7a",
                                 lw=1.0, linestyle="--"))
    users = [(r, p) for r, row in enumerate(rows) for p in row
             if p in ("fitting", "comparison", "design", "identify")]
    for r, _ in users:
        y = top - 0.62 * r
        ax.add_patch(FancyArrowPatch((7.45, y), (px + 0.2, py + box_h / 2), color="#9aa7c0",
                                     lw=0.6, arrowstyle="-|>", mutation_scale=7))
    ax.text(px, py + box_h / 2 + 0.15, "the stages above take any model through it",
            fontsize=7, color="#444")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=130)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs/images/architecture.png")
    args = parser.parse_args(argv)
    draw(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The paper's plate question from Python.

A steel plate whose model is 30 % too soft in one region is "tested" (ten modes at a grid of
sensors, with noise), correlated with its model (Table 1), assessed a priori by the residue
estimators (Table 2), studied as sensors are removed (Figure 1), localised and updated. This
script runs the study through femu's Python module and plots Table 1, Figure 1 and the error
map with matplotlib.

    python examples/python/plate_question.py [OUT] [--quick]

writes OUT/table1.png, OUT/figure1.png and OUT/error_map.png (and femu's own report files).
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import femu  # noqa: E402


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    out = pathlib.Path(args[0] if args else "femu-demo-python")
    report = femu.run_demo(out, quick="--quick" in sys.argv, progress=lambda s: print("..", s))

    # Table 1: paired modes, frequency errors and MAC
    pairs = report["table1"]["pairing"]["pairs"]
    test = [p["test"] + 1 for p in pairs]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.5))
    a1.bar(test, [100 * p["frequency_error"] for p in pairs])
    a1.set_xlabel("test mode")
    a1.set_ylabel("(f model - f test) / f test, %")
    a1.set_title("Table 1: frequency errors")
    a2.bar(test, [p["mac"] for p in pairs])
    a2.set_ylim(0.9, 1.0)
    a2.set_xlabel("test mode")
    a2.set_ylabel("MAC")
    a2.set_title("Table 1: MAC of the paired modes")
    fig.tight_layout()
    fig.savefig(out / "table1.png", dpi=120)

    # Figure 1: the estimator rho_M of each mode against the number of sensors, per expansion
    points = report["figure1"]
    fig, ax = plt.subplots(figsize=(6, 4))
    for method in sorted({p["method"] for p in points}):
        for mode in sorted({p["mode"] for p in points}):
            pts = sorted(
                (p["sensors"], p["rho_m"])
                for p in points
                if p["method"] == method and p["mode"] == mode
            )
            if pts:
                s, r = zip(*pts)
                ax.semilogy(s, np.sqrt(r) / (2 * np.pi), marker=".", label=f"{method}, mode {mode + 1}")
    ax.set_xlabel("sensors")
    ax.set_ylabel("sqrt(rho_M) / 2 pi, Hz")
    ax.set_title("Figure 1: the estimate as sensors are removed")
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(out / "figure1.png", dpi=120)

    # the error map: how much of the residual each region explains, and the regions selected
    ranking = sorted(report["localisation"]["ranking"], key=lambda r: r["group"])
    selected = set(report["localisation"]["selected"])
    fig, ax = plt.subplots(figsize=(6, 3))
    ax.bar(
        [r["name"] for r in ranking],
        [r["explained"] for r in ranking],
        color=["tab:red" if r["group"] in selected else "tab:gray" for r in ranking],
    )
    name, value = report["true_parameter"]
    ax.set_title(f"error map (true error: {name}, {value:+.0%}); red: selected")
    ax.set_ylabel("share of the residual explained")
    fig.tight_layout()
    fig.savefig(out / "error_map.png", dpi=120)

    judgement = report["truth_check"]["judgement"]
    print(f"wrote {out}/table1.png, figure1.png, error_map.png")
    print(f"does the updated model tell the truth? {judgement['verdict']} ({judgement['rule']})")


if __name__ == "__main__":
    main()

"""Typical use of femu, checked by `mypy --strict` against the package's stubs in CI (not run)."""

from typing import Any, Dict, List

import numpy as np
import numpy.typing as npt

import femu


def lowest_frequencies(path: str, count: int) -> List[float]:
    model: femu.Model = femu.read_model(path, lumped=False)
    modes: femu.Modes = model.modes(count)
    assert modes.sturm["verified"]
    return [float(f) for f in modes.frequencies_hz]


def table2(model: femu.Model, test_path: str) -> List[Dict[str, Any]]:
    test = femu.read_test(test_path, model, test_units=0.001)
    x: npt.NDArray[np.float64] = femu.expand(model, test, method="min-residual")
    assert x.shape[0] == model.free_count
    out = femu.estimate(model, test, expansion="dynamic", count=20)
    rows: List[Dict[str, Any]] = out["rows"]
    return rows


def from_arrays(model: femu.Model) -> femu.Test:
    shapes = np.zeros((2, 1))
    shapes[0, 0] = 1.0
    dirs = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    t = femu.Test.from_arrays(model, [1, 2], dirs, [100.0], shapes)
    mac = femu.mac(t.shapes)
    assert mac.shape == (1, 1)
    return t


def demo(out: str) -> str:
    report = femu.run_demo(out, quick=True, progress=print)
    return str(report["truth_check"]["judgement"]["verdict"])


try:
    femu.read_model("missing.inp")
except femu.FemuError as e:
    message: str = str(e)

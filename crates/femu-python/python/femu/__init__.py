"""femu: finite element model updating and test-analysis correlation.

The Python face of femu's Rust library: models read from the files engineers have (Abaqus and
CalculiX decks, Nastran bulk data, Gmsh meshes, universal files), ``K`` and ``M`` as
``scipy.sparse.csc_matrix``, Sturm-verified modes, test modes from files or numpy arrays, MAC
matrices, expansion and the paper's a priori estimators.

>>> import femu
>>> model = femu.read_model("plate.inp")                      # doctest: +SKIP
>>> modes = model.modes(20)                                    # doctest: +SKIP
>>> test = femu.read_test("test.unv", model)                   # doctest: +SKIP
>>> table = femu.estimate(model, test)["rows"]                 # doctest: +SKIP

Errors are :class:`femu.FemuError` with femu's message (file and line, node, element).
"""

from ._femu import (
    FemuError,
    Model,
    Modes,
    Results,
    Test,
    correlate,
    estimate,
    expand,
    frf,
    mac,
    read_model,
    read_results,
    read_test,
    removal_study,
    run_demo,
    update,
)

__all__ = [
    "FemuError",
    "Model",
    "Modes",
    "Results",
    "Test",
    "correlate",
    "estimate",
    "expand",
    "frf",
    "mac",
    "read_model",
    "read_results",
    "read_test",
    "removal_study",
    "run_demo",
    "update",
]

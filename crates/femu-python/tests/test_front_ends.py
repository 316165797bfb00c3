"""One workflow, one default: the same estimate and the same update run through the command line
(`femu estimate`, `femu update`), a study file (`femu run`) and the Python binding give the same
JSON, field by field. The model is a clamped steel bar in four slabs written here; the "test" is
the bar with slab G1 20 % softer, solved by femu and read at the top face in y and z."""

import json
import os
import pathlib
import subprocess

import pytest

import femu

ROOT = pathlib.Path(__file__).resolve().parents[3]
# the command line built by `cargo test --workspace` (CI runs it before these tests)
FEMU = pathlib.Path(os.environ.get("FEMU_BIN", ROOT / "target" / "debug" / "femu"))
NX, NY, NZ, SIZE = 8, 3, 2, (0.4, 0.06, 0.03)
SETS = ["G0", "G1", "G2", "G3"]


def slab_deck(path, soft_set=None, factor=0.8):
    """A clamped steel hex8 bar, elements in four slabs along x (sets G0..G3), each with its own
    section; `soft_set` gets `factor` times Young's modulus."""
    lx, ly, lz = SIZE
    node = lambda i, j, k: 1 + i + (NX + 1) * (j + (NY + 1) * k)
    lines = ["*NODE"]
    for k in range(NZ + 1):
        for j in range(NY + 1):
            for i in range(NX + 1):
                lines.append(f"{node(i, j, k)}, {lx * i / NX!r}, {ly * j / NY!r}, {lz * k / NZ!r}")
    e = 1
    for s, name in enumerate(SETS):
        lines.append(f"*ELEMENT, TYPE=C3D8, ELSET={name}")
        for k in range(NZ):
            for j in range(NY):
                for i in range(2 * s, 2 * s + 2):
                    c = [
                        node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k),
                        node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1),
                        node(i, j + 1, k + 1),
                    ]
                    lines.append(", ".join(str(v) for v in [e] + c))
                    e += 1
    for name in SETS:
        young = 2.1e11 * (factor if name == soft_set else 1.0)
        lines += [f"*MATERIAL, NAME=M{name}", "*ELASTIC", f"{young!r}, 0.3", "*DENSITY", "7850",
                  f"*SOLID SECTION, ELSET={name}, MATERIAL=M{name}"]
    lines.append("*BOUNDARY")
    for k in range(NZ + 1):
        for j in range(NY + 1):
            lines.append(f"{node(0, j, k)}, 1, 3")
    path.write_text("\n".join(lines) + "\n")
    return path


def without_timings(v):
    """The value with every wall-clock field (`seconds`) removed: they differ run to run."""
    if isinstance(v, dict):
        return {k: without_timings(x) for k, x in v.items() if k != "seconds"}
    if isinstance(v, list):
        return [without_timings(x) for x in v]
    return v


def assert_same(a, b, path="$"):
    """Field by field: the same keys, lengths, strings, flags and numbers. Exactly: the three
    front ends run one pipeline with one set of defaults, deterministic for a seed (the wheel and
    the command line are two builds of the same code; IEEE arithmetic without fast-math gives the
    same bits)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and sorted(a) == sorted(b), f"{path}: keys {sorted(a)} {sorted(b)}"
        for k in a:
            assert_same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{path}[{i}]")
    else:
        assert a == b, f"{path}: {a!r} {b!r}"


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    d = tmp_path_factory.mktemp("front_ends")
    deck = slab_deck(d / "bar.inp")
    real = femu.read_model(slab_deck(d / "real.inp", soft_set="G1"))
    modes = real.modes(6)
    lx, ly, lz = SIZE
    rows = {(int(n), int(c)): f for f, (n, c) in enumerate(real.dofs)}
    top = [int(n) for n, p in zip(real.node_ids, real.coords) if abs(p[2] - lz) < 1e-12 and p[0] > 0]
    lines = ["mode,frequency_hz,node,direction,value"]
    for j in range(6):
        for n in top:
            for c, name in ((1, "y"), (2, "z")):
                lines.append(f"{j + 1},{float(modes.frequencies_hz[j])!r},{n},{name},{float(modes.vectors[rows[(n, c)], j])!r}")
    (d / "test.csv").write_text("\n".join(lines) + "\n")
    (d / "study.toml").write_text(
        'model = "bar.inp"\ntest = "test.csv"\n[expansion]\nmethod = "dynamic"\n'
        '[update]\nsets = ["G0", "G1", "G2", "G3"]\n'
    )
    assert FEMU.is_file(), f"{FEMU}: build the command line first (cargo build -p femu-cli)"
    run = lambda *args: subprocess.run([str(FEMU), *map(str, args), "--quiet"], cwd=d,
                                       capture_output=True, text=True)
    # the study file solves max(2 n + 4, n + 10) = 16 modes once for every step: the command line
    # and Python are asked for as many
    done = run("estimate", "bar.inp", "test.csv", "--count", 16, "--json", "estimate.json")
    assert done.returncode == 0, done.stderr
    done = run("update", "bar.inp", "test.csv", "--sets", ",".join(SETS), "--json", "update.json")
    assert done.returncode == 0, done.stderr
    done = run("run", "study.toml", "--out", "study")
    assert done.returncode == 0, done.stderr
    return d


def read(path):
    return json.loads(path.read_text())


def test_the_estimate_is_one_pipeline(case):
    model = femu.read_model(case / "bar.inp")
    test = femu.read_test(case / "test.csv", model)
    py = femu.estimate(model, test, count=16)
    cli = read(case / "estimate.json")
    study = read(case / "study" / "estimate.json")
    assert len(cli) == 6
    assert_same(py["assessments"], cli)
    assert_same(study, py)


def test_the_update_is_one_pipeline_with_one_default(case):
    model = femu.read_model(case / "bar.inp")
    test = femu.read_test(case / "test.csv", model)
    # no `tuned`: the default (all but the last third: 4 of 6) is the command line's and the
    # study file's
    py = without_timings(femu.update(model, test, SETS))
    cli = without_timings(read(case / "update.json"))
    study = without_timings(read(case / "study" / "update.json"))
    assert len(py["truth_check"]["modes"]) == 6
    assert_same(py, cli)
    assert_same(study, py)

"""One workflow, one default: the same estimate, the same update and the same FRF correlation run
through the command line (`femu estimate`, `femu update`, `femu frf`), a study file (`femu run`)
and the Python binding give the same JSON, field by field. The model is a clamped steel bar in
four slabs written here; the "test" is the bar with slab G1 20 % softer, solved by femu and read
at the top face in y and z, and its FRFs solved directly by numpy (a universal file written by
pyuff)."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest
import pyuff

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


LOSS = 0.02


def frf_file(model, path, top_hz):
    """Receptances of `model` by numpy's dense direct solve of (K (1 + i eta) - w^2 M) x = f, at
    the tip's top corner in z (the reference) and three top-face DOFs, on 120 lines to past the
    third mode, written by pyuff as dataset 58 (complex double, even abscissa)."""
    k, m = model.K.toarray(), model.M.toarray()
    rows = {(int(n), int(c)): f for f, (n, c) in enumerate(model.dofs)}
    lx, ly, lz = SIZE
    at = lambda x, y, z: next(int(n) for n, p in zip(model.node_ids, model.coords)
                             if np.allclose(p, (x, y, z)))
    ref = at(lx, 0.0, lz)
    responses = [(ref, 3), (at(lx / 2, 0.0, lz), 3), (at(lx, ly, lz), 2)]
    lines = 2.5 + 2.5 * np.arange(int(1.1 * top_hz / 2.5))
    force = np.zeros(k.shape[0])
    force[rows[(ref, 2)]] = 1.0
    x = np.array([np.linalg.solve(k * (1 + 1j * LOSS) - (2 * np.pi * f) ** 2 * m, force)
                  for f in lines])
    sets = []
    for i, (node, d) in enumerate(responses):
        sets.append({
            "type": 58, "binary": 0, "func_type": 4, "rsp_node": node, "rsp_dir": d,
            "ref_node": ref, "ref_dir": 3, "x": lines, "data": x[:, rows[(node, d - 1)]],
            "abscissa_spacing": 1, "id1": f"H{i + 1}", "rsp_ent_name": "bar",
            "ref_ent_name": "bar", "abscissa_spec_data_type": 18,
            "ordinate_spec_data_type": 8, "orddenom_spec_data_type": 13,
            "z_axis_spec_data_type": 0, "abscissa_axis_units_lab": "Hz",
        })
    pyuff.UFF(str(path)).write_sets(sets, mode="add")


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
    frf_file(real, d / "frf.uff", modes.frequencies_hz[2])
    (d / "study.toml").write_text(
        'model = "bar.inp"\ntest = "test.csv"\n[expansion]\nmethod = "dynamic"\n'
        '[update]\nsets = ["G0", "G1", "G2", "G3"]\n'
        '[frf]\nfile = "frf.uff"\nloss_factor = 0.02\n'
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
    done = run("frf", "bar.inp", "frf.uff", "--loss-factor", 0.02, "--json", "frf.json")
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


def test_the_frf_correlation_is_one_pipeline(case):
    model = femu.read_model(case / "bar.inp")
    py = femu.frf(model, case / "frf.uff", loss_factor=LOSS)
    cli = read(case / "frf.json")
    study = read(case / "study" / "frf.json")
    assert len(py["functions"]) == 3 and py["residual_flexibility"]
    assert_same(py, cli)
    assert_same(study, py)
    # the measured bar itself against numpy's direct solve: the same curves
    real = femu.frf(femu.read_model(case / "real.inp"), case / "frf.uff", loss_factor=LOSS)
    assert min(f["frac"] for f in real["functions"]) > 0.999
    assert min(line["csac"] for line in real["lines"]) > 0.999
    # solved directly at each line, as numpy solved it: the same curves to round-off
    direct = femu.frf(
        femu.read_model(case / "real.inp"), case / "frf.uff", loss_factor=LOSS, direct=True
    )
    assert direct["direct"] and direct["backward_error"] < 1e-13
    assert min(f["frac"] for f in direct["functions"]) > 1 - 1e-9
    # and the nominal bar, whose G1 is 20 % stiffer, misses the resonances
    assert min(f["frac"] for f in py["functions"]) < 0.9


def test_the_frf_update_is_one_pipeline(case):
    """Updating from the FRFs (numpy's direct solve of the bar whose G1 has 0.8 of the modulus,
    loss factor 0.02) over the four slabs from a loss factor of 0.01: the command line, a study
    file's `[frf]` and Python give the same JSON; G1 is found (-0.2 to 1e-4), the others stay at
    0, the loss factor is 0.02, and the held-out lines' error falls; a loss factor per slab finds
    0.02 in each, the same from Python and the command line."""
    run = lambda *args: subprocess.run([str(FEMU), *map(str, args), "--quiet"], cwd=case,
                                       capture_output=True, text=True)
    done = run("frf", "bar.inp", "frf.uff", "--loss-factor", 0.01, "--update", ",".join(SETS),
               "--update-all", "--json", "frf_update.json")
    assert done.returncode == 0, done.stderr
    (case / "study_frf.toml").write_text(
        'model = "bar.inp"\ntest = "test.csv"\n[frf]\nfile = "frf.uff"\nloss_factor = 0.01\n'
        'update = ["G0", "G1", "G2", "G3"]\nupdate_all = true\n'
    )
    done = run("run", "study_frf.toml", "--out", "study_frf")
    assert done.returncode == 0, done.stderr
    model = femu.read_model(case / "bar.inp")
    py = femu.frf(model, case / "frf.uff", loss_factor=0.01, update=SETS, update_all=True)
    assert_same(py, read(case / "frf_update.json"))
    assert_same(read(case / "study_frf" / "frf.json"), py)
    report = (case / "study_frf" / "report.md").read_text()
    assert "# correlation" in report and "# frequency responses" in report
    assert "Updating from FRFs" in report
    u = py["update"]
    assert u["result"]["names"] == [f"k:{s}" for s in SETS]
    want = [0.0, -0.2, 0.0, 0.0]
    assert np.allclose(u["result"]["theta"], want, atol=1e-4), u["result"]
    assert abs(u["result"]["damping"]["loss_factor"] - LOSS) < 1e-5
    before, after = u["held_out_error"]
    assert after < 1e-3 * before
    with pytest.raises(femu.FemuError, match="NOPE"):
        femu.frf(model, case / "frf.uff", update=["G1", "NOPE"])
    # a loss factor per slab (the bar's is one: each finds it), from Python as from the CLI
    per = femu.frf(model, case / "frf.uff", loss_factor=0.01, update=SETS, update_all=True,
                   loss_factor_per_set=True)
    done = run("frf", "bar.inp", "frf.uff", "--loss-factor", 0.01, "--update", ",".join(SETS),
               "--update-all", "--loss-factor-per-set", "--json", "frf_per_set.json")
    assert done.returncode == 0, done.stderr
    assert_same(per, read(case / "frf_per_set.json"))
    groups = per["update"]["result"]["damping"]["group_loss_factors"]["groups"]
    assert np.allclose(groups, [LOSS] * len(SETS), atol=1e-5), groups


def test_another_solvers_matrices_are_a_model_everywhere(case):
    """The bar's K and M written by `femu matrices` (MatrixMarket, DOF table, node table) are a
    model for the command line, a study file and Python alike: the same estimate from each, the
    same frequency intervals as the deck's (the residues do not depend on where K and M came
    from); and the same update over matrix groups (each group's export with its modulus doubled)
    from the command line and Python, with the deck's selection and parameters."""
    run = lambda *args: subprocess.run([str(FEMU), *map(str, args), "--quiet"], cwd=case,
                                       capture_output=True, text=True)
    done = run("matrices", "bar.inp", "--out", "bar")
    assert done.returncode == 0, done.stderr
    done = run("estimate", "bar_K.mtx", "test.csv", "--count", 16, "--json", "estimate_mtx.json")
    assert done.returncode == 0, done.stderr
    (case / "study_mtx.toml").write_text(
        'model = "bar_K.mtx"\ntest = "test.csv"\nnodes = "bar_nodes.csv"\n'
        '[expansion]\nmethod = "dynamic"\n'
    )
    done = run("run", "study_mtx.toml", "--out", "study_mtx")
    assert done.returncode == 0, done.stderr
    model = femu.read_model(case / "bar_K.mtx", nodes=case / "bar_nodes.csv")
    with pytest.raises(femu.FemuError, match="total mass is not known"):
        model.total_mass
    test = femu.read_test(case / "test.csv", model)
    py = femu.estimate(model, test, count=16)
    assert_same(py["assessments"], read(case / "estimate_mtx.json"))
    assert_same(read(case / "study_mtx" / "estimate.json"), py)
    deck = femu.read_model(case / "bar.inp")
    own = femu.estimate(deck, femu.read_test(case / "test.csv", deck), count=16)
    for a, b in zip(py["assessments"], own["assessments"]):
        assert np.allclose(a["frequency_interval_hz"], b["frequency_interval_hz"], rtol=1e-9)
    with pytest.raises(Exception, match="NAME=FILE"):
        femu.update(model, test, SETS)
    groups = []
    for name in SETS:
        slab_deck(case / f"bar_{name}.inp", soft_set=name, factor=2.0)
        done = run("matrices", f"bar_{name}.inp", "--out", f"bar_{name}")
        assert done.returncode == 0, done.stderr
        groups.append(f"{name}=bar_{name}_K.mtx")
    done = run("update", "bar_K.mtx", "test.csv", "--sets", ",".join(groups), "--json",
               "update_mtx.json")
    assert done.returncode == 0, done.stderr
    py = without_timings(femu.update(model, test, groups))
    assert_same(py, without_timings(read(case / "update_mtx.json")))
    own = femu.update(deck, femu.read_test(case / "test.csv", deck), SETS)
    assert py["updated_sets"] == own["updated_sets"]
    assert np.allclose(py["result"]["theta"], own["result"]["theta"], rtol=1e-6, atol=1e-9)


def test_another_solvers_modes_are_the_model_side_everywhere(case):
    """CalculiX's modes of the bar (a .frd from *NODE FILE, U) correlated with the test by the
    command line, a study file and Python: the same report; and the same pairs as femu's own modes of the
    deck, with frequencies within 1e-6 of femu's (two codes on one deck)."""
    deck = (case / "bar.inp").read_text()
    (case / "ccx").mkdir(exist_ok=True)
    (case / "ccx" / "bar.inp").write_text(deck + "*STEP\n*FREQUENCY\n12\n*NODE FILE\nU\n*END STEP\n")
    ccx = subprocess.run(["ccx", "-i", "bar"], cwd=case / "ccx", capture_output=True, text=True)
    assert ccx.returncode == 0, ccx.stdout
    frd = case / "ccx" / "bar.frd"
    done = subprocess.run([str(FEMU), "correlate", str(frd), "test.csv", "--json", "frd.json",
                           "--quiet"], cwd=case, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    results = femu.read_results(frd)
    assert len(results) == 12 and results.shapes.shape == (3 * len(results.node_ids), 12)
    py = femu.correlate(results, femu.read_test(case / "test.csv", results))
    assert_same(py, read(case / "frd.json"))
    (case / "study_frd.toml").write_text('model = "ccx/bar.frd"\ntest = "test.csv"\n')
    done = subprocess.run([str(FEMU), "run", "study_frd.toml", "--out", "study_frd", "--quiet"],
                          cwd=case, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert_same(read(case / "study_frd" / "correlation.json"), py)
    model = femu.read_model(case / "bar.inp")
    own = femu.correlate(model, femu.read_test(case / "test.csv", model), count=12)
    assert [(p["test"], p["model"]) for p in py["pairing"]["pairs"]] == \
        [(p["test"], p["model"]) for p in own["pairing"]["pairs"]]
    assert np.allclose(py["f_model"], own["f_model"], rtol=1e-6)


def test_gmsh_shells_are_one_definition(tmp_path):
    """A Gmsh plate of quadrangles (physical surface "plate", clamped physical curve "edge") made
    shells by `shells={"plate": 0.05}` in Python and by `--shell plate=0.05` on the command line:
    the same frequencies; a group that is not a surface group is refused, naming the groups."""
    n = 8
    node = lambda i, j: 1 + i + (n + 1) * j
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "2",
             '1 2 "edge"', '2 1 "plate"', "$EndPhysicalNames", "$Nodes", str((n + 1) ** 2)]
    lines += [f"{node(i, j)} {10.0 * i / n!r} {10.0 * j / n!r} 0" for j in range(n + 1)
              for i in range(n + 1)]
    elements = [f"1 2 2 2 {node(0, j)} {node(0, j + 1)}" for j in range(n)]
    elements += [f"3 2 1 1 {node(i, j)} {node(i + 1, j)} {node(i + 1, j + 1)} {node(i, j + 1)}"
                 for j in range(n) for i in range(n)]
    lines += ["$EndNodes", "$Elements", str(len(elements))]
    lines += [f"{k + 1} {e}" for k, e in enumerate(elements)]
    lines += ["$EndElements"]
    msh = tmp_path / "plate.msh"
    msh.write_text("\n".join(lines) + "\n")
    material = dict(young=2e11, poisson=0.3, density=8000.0)
    model = femu.read_model(msh, fix=["edge"], shells={"plate": 0.05}, **material)
    py = np.asarray(model.modes(4).frequencies_hz)
    done = subprocess.run([str(FEMU), "modes", str(msh), "--young", "2e11", "--poisson", "0.3",
                           "--density", "8000", "--fix", "edge", "--shell", "plate=0.05",
                           "--count", "4", "--json", str(tmp_path / "m.json"), "--quiet"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    cli = np.asarray(read(tmp_path / "m.json")["frequencies_hz"])
    assert np.allclose(py, cli, rtol=1e-12, atol=0.0)
    # NAFEMS FV16's first frequency, 0.421 Hz, within the coarse mesh's error
    assert abs(py[0] / 0.421 - 1) < 0.02
    with pytest.raises(femu.FemuError, match="plate"):
        femu.read_model(msh, fix=["edge"], shells={"edge": 0.05}, **material)
    # a study file's [shells]: the model's own modes as the test pair with it exactly
    modes = model.modes(4)
    rows = {(int(n), int(c)): f for f, (n, c) in enumerate(model.dofs)}
    free_edge = [node(n, j) for j in range(0, n + 1, 2)]
    csv = ["mode,frequency_hz,node,direction,value"]
    for k in range(4):
        for nd in free_edge:
            csv.append(f"{k + 1},{float(modes.frequencies_hz[k])!r},{nd},z,"
                       f"{float(modes.vectors[rows[(nd, 2)], k])!r}")
    (tmp_path / "test.csv").write_text("\n".join(csv) + "\n")
    (tmp_path / "study.toml").write_text(
        'model = "plate.msh"\ntest = "test.csv"\nfix = ["edge"]\n'
        '[material]\nyoung = 2e11\npoisson = 0.3\ndensity = 8000.0\n'
        '[shells]\nplate = 0.05\n'
    )
    done = subprocess.run([str(FEMU), "run", str(tmp_path / "study.toml"), "--out",
                           str(tmp_path / "study"), "--quiet"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    pairs = read(tmp_path / "study" / "correlation.json")["pairing"]["pairs"]
    assert len(pairs) == 4
    assert all(p["mac"] > 1 - 1e-9 for p in pairs)


def test_gmsh_beams_are_one_definition(tmp_path):
    """A Gmsh cantilever of 2-node lines (physical curve "frame", clamped physical point "root")
    made beams by `beams={"frame": "rect:0.02,0.04"}` in Python and `--beam` on the command line:
    the same frequencies, the first Euler-Bernoulli's to 0.1 %."""
    n = 20
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "2", '0 1 "root"',
             '1 2 "frame"', "$EndPhysicalNames", "$Nodes", str(n + 1)]
    lines += [f"{i + 1} {i / n!r} 0 0" for i in range(n + 1)]
    lines += ["$EndNodes", "$Elements", str(n + 1), "1 15 2 1 1 1"]
    lines += [f"{i + 2} 1 2 2 2 {i + 1} {i + 2}" for i in range(n)]
    lines += ["$EndElements"]
    msh = tmp_path / "beam.msh"
    msh.write_text("\n".join(lines) + "\n")
    model = femu.read_model(msh, young=2.1e11, poisson=0.3, density=7850.0, fix=["root"],
                            beams={"frame": "rect:0.02,0.04"})
    py = np.asarray(model.modes(4).frequencies_hz)
    done = subprocess.run([str(FEMU), "modes", str(msh), "--young", "2.1e11", "--poisson", "0.3",
                           "--density", "7850", "--fix", "root", "--beam",
                           "frame=rect:0.02,0.04", "--count", "4", "--json",
                           str(tmp_path / "m.json"), "--quiet"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert np.allclose(py, read(tmp_path / "m.json")["frequencies_hz"], rtol=1e-12, atol=0.0)
    e, rho, a, i = 2.1e11, 7850.0, 0.02 * 0.04, 0.04 * 0.02 ** 3 / 12
    f1 = 1.8751 ** 2 / (2 * np.pi) * np.sqrt(e * i / (rho * a))
    assert abs(py[0] / f1 - 1) < 1e-3
    with pytest.raises(femu.FemuError, match="RECT, CIRC and PIPE"):
        femu.read_model(msh, young=2.1e11, poisson=0.3, density=7850.0, fix=["root"],
                        beams={"frame": "ibeam:0.1,0.2"})


def test_a_gmsh_stiffened_panel_updates_its_thickness(tmp_path):
    """A free aluminium panel of Gmsh quadrangles (shells, 2 mm) with a beam stiffener along its
    middle (lines sharing the panel's nodes): the "real" panel 2.2 mm thick, its elastic modes 1-10
    read in z at 25 nodes; updating the thickness of the panel (`t:plate`: bending with its cube,
    membrane and mass linearly) and the stiffener's stiffness finds +0.1 and 0, and the truth
    check agrees. (The test is made by femu's own elements: the shells and beams are verified
    against NAFEMS and analytic values elsewhere; this checks a mixed model's parameters.)"""
    n = 12
    node = lambda i, j: 1 + i + (n + 1) * j
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "2",
             '1 2 "stiffener"', '2 1 "plate"', "$EndPhysicalNames", "$Nodes", str((n + 1) ** 2)]
    lines += [f"{node(i, j)} {0.6 * i / n!r} {0.4 * j / n!r} 0" for j in range(n + 1)
              for i in range(n + 1)]
    els = [f"3 2 1 1 {node(i, j)} {node(i + 1, j)} {node(i + 1, j + 1)} {node(i, j + 1)}"
           for j in range(n) for i in range(n)]
    els += [f"1 2 2 2 {node(i, n // 2)} {node(i + 1, n // 2)}" for i in range(n)]
    lines += ["$EndNodes", "$Elements", str(len(els))]
    lines += [f"{k + 1} {e}" for k, e in enumerate(els)] + ["$EndElements"]
    msh = tmp_path / "panel.msh"
    msh.write_text("\n".join(lines) + "\n")
    material = dict(young=7e10, poisson=0.33, density=2700.0)
    stiffener = {"stiffener": "rect:0.01,0.02@0,0,1"}
    real = femu.read_model(msh, shells={"plate": 0.0022}, beams=stiffener, **material)
    modes = real.modes(16)
    rows = {(int(a), int(c)): f for f, (a, c) in enumerate(real.dofs)}
    csv = ["mode,frequency_hz,node,direction,value"]
    for k in range(6, 16):
        for nd in (node(i, j) for i in range(0, n + 1, 3) for j in range(0, n + 1, 3)):
            csv.append(f"{k - 5},{float(modes.frequencies_hz[k])!r},{nd},z,"
                       f"{float(modes.vectors[rows[(nd, 2)], k])!r}")
    (tmp_path / "test.csv").write_text("\n".join(csv) + "\n")
    model = femu.read_model(msh, shells={"plate": 0.002}, beams=stiffener, **material)
    test = femu.read_test(tmp_path / "test.csv", model)
    r = femu.update(model, test, ["t:plate", "stiffener"], discretisation=False)
    assert r["result"]["names"] == ["t:plate", "k:stiffener"]
    assert np.allclose(r["result"]["theta"], [0.1, 0.0], atol=1e-6), r["result"]["theta"]
    assert r["truth_check"]["judgement"]["verdict"] == "agrees"


def write_op4_text(path, matrices):
    """Nastran's OUTPUT4 text format, written here from its description (a third writer, beside
    femu's test kit and Nastran's own files): `4I8,A8` headers and `1P,3E23.16` values, each
    column's strings of consecutive rows behind one-word headers IROW + 65536 (L + 1)."""
    lines = []
    for name, n, columns in matrices:
        lines.append(f"{n:8d}{n:8d}{6:8d}{2:8d}{name:<8s}1P,3E23.16")
        for j, col in enumerate(columns):
            if not col:
                continue
            strings = []
            for r, v in sorted(col):
                if strings and strings[-1][0] + len(strings[-1][1]) == r:
                    strings[-1][1].append(v)
                else:
                    strings.append((r, [v]))
            nw = sum(1 + 2 * len(vals) for _, vals in strings)
            lines.append(f"{j + 1:8d}{0:8d}{nw:8d}")
            for first, vals in strings:
                lines.append(f"{first + 1 + 65536 * (2 * len(vals) + 1):12d}")
                for k in range(0, len(vals), 3):
                    lines.append("".join(f"{v:23.16E}" for v in vals[k:k + 3]))
        lines.append(f"{n + 1:8d}{1:8d}{1:8d}")
        lines.append(f"{1.0:23.16E}")
    path.write_text("\n".join(lines) + "\n")


def mtx_columns(path):
    """The columns of a symmetric MatrixMarket coordinate file (one triangle), both triangles."""
    rows = [l for l in path.read_text().splitlines() if l and not l.startswith("%")]
    n = int(rows[0].split()[0])
    cols = [[] for _ in range(n)]
    for l in rows[1:]:
        i, j, v = l.split()
        i, j, v = int(i) - 1, int(j) - 1, float(v)
        cols[j].append((i, v))
        if i != j:
            cols[i].append((j, v))
    return n, cols


def test_nastran_op4_matrices_are_a_model_everywhere(case):
    """The bar's K and M as Nastran's OUTPUT4 text (KAA, MAA) with their DOF table are a model
    for the command line and Python: the same estimate as from the MatrixMarket files they were
    written from (the values' 17 digits are the doubles'), and `femu info` lists the matrices."""
    run = lambda *args: subprocess.run([str(FEMU), *map(str, args), "--quiet"], cwd=case,
                                       capture_output=True, text=True)
    done = run("matrices", "bar.inp", "--out", "bar")
    assert done.returncode == 0, done.stderr
    n, k = mtx_columns(case / "bar_K.mtx")
    _, m = mtx_columns(case / "bar_M.mtx")
    write_op4_text(case / "op4bar.op4", [("KAA", n, k), ("MAA", n, m)])
    (case / "op4bar_dofs.csv").write_text((case / "bar_dofs.csv").read_text())
    info = subprocess.run([str(FEMU), "info", "op4bar.op4"], cwd=case, capture_output=True,
                          text=True)
    assert info.returncode == 0, info.stderr
    assert f"matrix KAA: {n} x {n}, symmetric" in info.stdout, info.stdout
    done = run("estimate", "op4bar.op4", "test.csv", "--count", 16, "--nodes", "bar_nodes.csv",
               "--json", "estimate_op4.json")
    assert done.returncode == 0, done.stderr
    done = run("estimate", "bar_K.mtx", "test.csv", "--count", 16, "--json", "estimate_mtx.json")
    assert done.returncode == 0, done.stderr
    model = femu.read_model(case / "op4bar.op4", nodes=case / "bar_nodes.csv")
    py = femu.estimate(model, femu.read_test(case / "test.csv", model), count=16)
    assert_same(py["assessments"], read(case / "estimate_op4.json"))
    for a, b in zip(py["assessments"], read(case / "estimate_mtx.json")):
        assert np.allclose(a["frequency_interval_hz"], b["frequency_interval_hz"], rtol=1e-12)

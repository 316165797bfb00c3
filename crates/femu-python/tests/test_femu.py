"""femu's Python module against independent Python computations: scipy's eigsh on the exported
K and M, MAC and rho_M in numpy, a universal file written by pyuff read back, errors with their
messages, and dict/JSON round trips."""

import json
import os
import pathlib

import numpy as np
import pytest
import scipy.sparse.linalg as sla

import femu

ROOT = pathlib.Path(__file__).resolve().parents[3]


def box_deck(path, nx=6, ny=3, nz=2, size=(0.3, 0.06, 0.03)):
    """A clamped steel hex8 box written here as a CalculiX deck (node ids 1.., x fastest)."""
    lx, ly, lz = size
    node = lambda i, j, k: 1 + i + (nx + 1) * (j + (ny + 1) * k)
    lines = ["*NODE"]
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                lines.append(f"{node(i, j, k)}, {lx * i / nx!r}, {ly * j / ny!r}, {lz * k / nz!r}")
    lines.append("*ELEMENT, TYPE=C3D8, ELSET=ALL")
    e = 1
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                c = [
                    node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k),
                    node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1),
                    node(i, j + 1, k + 1),
                ]
                lines.append(", ".join(str(v) for v in [e] + c))
                e += 1
    lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC", "2.1e11, 0.3", "*DENSITY", "7850",
              "*SOLID SECTION, ELSET=ALL, MATERIAL=STEEL", "*BOUNDARY"]
    for k in range(nz + 1):
        for j in range(ny + 1):
            lines.append(f"{node(0, j, k)}, 1, 3")
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    return femu.read_model(box_deck(tmp_path_factory.mktemp("m") / "box.inp"))


def test_matrices_and_modes_against_scipy(model):
    K, M = model.K, model.M
    n = model.free_count
    assert K.shape == (n, n) and M.shape == (n, n)
    assert abs(K - K.T).max() <= 1e-12 * abs(K).max()
    assert model.dofs.shape == (n, 2)
    # rigid translation along x carries the whole mass (the clamped face's DOFs are gone)
    assert model.total_mass == pytest.approx(7850 * 0.3 * 0.06 * 0.03, rel=1e-12)
    modes = model.modes(8)
    ref = np.sort(sla.eigsh(K, k=8, M=M, sigma=0.0, which="LM")[0])
    np.testing.assert_allclose(modes.values, ref, rtol=1e-9)
    assert modes.sturm["verified"] and modes.sturm["count"] == 8
    phi = modes.vectors
    np.testing.assert_allclose(phi.T @ (M @ phi), np.eye(8), atol=1e-10)
    assert np.all(modes.residuals < 1e-8)
    np.testing.assert_allclose(
        modes.frequencies_hz, np.sqrt(modes.values) / (2 * np.pi), rtol=1e-14
    )


def test_block_size_changes_the_work_not_the_modes(model):
    K, M = model.K, model.M
    ref = np.sort(sla.eigsh(K, k=8, M=M, sigma=0.0, which="LM")[0])
    for block in (1, 2, 8):
        modes = model.modes(8, block_size=block)
        np.testing.assert_allclose(modes.values, ref, rtol=1e-9)
        e = modes.to_dict()["eigensolver"]
        assert e["block_size"] == block and e["factorizations"] == 2
        assert e["solved_vectors"] >= 8
    with pytest.raises(femu.FemuError, match="block size 0"):
        model.modes(8, block_size=0)


def numpy_mac(a, b):
    num = (a.T @ b) ** 2
    return num / np.outer(np.sum(a * a, axis=0), np.sum(b * b, axis=0))


def test_mac_against_numpy():
    rng = np.random.default_rng(1)
    a, b = rng.standard_normal((40, 5)), rng.standard_normal((40, 7))
    np.testing.assert_allclose(femu.mac(a, b), numpy_mac(a, b), rtol=1e-13)
    np.testing.assert_allclose(femu.mac(a), numpy_mac(a, a), rtol=1e-13)


def sensor_test(model, modes, count=4, shift=1.03, noise=0.01, seed=2):
    """Test modes at the top-face nodes in z: the model's shapes, frequencies 3 % high, noisy."""
    ids, x = model.node_ids, model.coords
    top = [int(i) for i, p in zip(ids, x) if abs(p[2] - 0.03) < 1e-12 and p[0] > 0]
    dofs = {(int(n), int(c)): f for f, (n, c) in enumerate(model.dofs)}
    rows = [dofs[(n, 2)] for n in top]
    rng = np.random.default_rng(seed)
    shapes = modes.vectors[rows, :count]
    shapes = shapes + noise * np.abs(shapes).max(axis=0) * rng.standard_normal(shapes.shape)
    freqs = shift * modes.frequencies_hz[:count]
    dirs = np.tile([0.0, 0.0, 1.0], (len(top), 1))
    return top, dirs, freqs, shapes


def test_estimate_rho_m_against_numpy(model):
    modes = model.modes(12)
    top, dirs, freqs, shapes = sensor_test(model, modes)
    test = femu.Test.from_arrays(model, top, dirs, list(freqs), shapes)
    assert len(test) == 4 and test.C.shape == (len(top), model.free_count)
    x = femu.expand(model, test, method="dynamic")
    # the expansion reproduces the readings: C x = y
    np.testing.assert_allclose(test.C @ x, shapes, rtol=1e-9, atol=1e-12)
    out = femu.estimate(model, test)
    K, M = model.K.toarray(), model.M.toarray()
    lam = (2 * np.pi * freqs) ** 2
    for j, row in enumerate(out["rows"]):
        r = K @ x[:, j] - lam[j] * (M @ x[:, j])
        rho_m = np.sqrt(r @ np.linalg.solve(M, r)) / np.sqrt(x[:, j] @ M @ x[:, j])
        assert row["rho_m"] == pytest.approx(rho_m, rel=1e-8)
        # Theorem 2, rigorous: a model eigenvalue within rho_M of the test's
        gap = np.min(np.abs(modes.values - lam[j]))
        assert gap <= rho_m * (1 + 1e-9)
    assert json.loads(json.dumps(out)) == out


def test_a_universal_file_written_by_pyuff(model, tmp_path):
    pyuff = pytest.importorskip("pyuff")
    modes = model.modes(6)
    top, _, freqs, shapes = sensor_test(model, modes, count=3, shift=1.0, noise=0.0)
    ids = list(model.node_ids)
    x = model.coords
    path = str(tmp_path / "test.unv")
    uff = pyuff.UFF(path)
    sel = [ids.index(n) for n in top]
    uff.write_sets(
        pyuff.prepare_15(
            node_nums=top,
            def_cs=[0] * len(top),
            disp_cs=[0] * len(top),
            color=[1] * len(top),
            x=[float(x[i][0]) for i in sel],
            y=[float(x[i][1]) for i in sel],
            z=[float(x[i][2]) for i in sel],
        ),
        mode="add",
    )
    for k in range(3):
        uff.write_sets(
            pyuff.prepare_55(
                model_type=1, analysis_type=2, data_ch=2, spec_data_type=8, data_type=2,
                n_data_per_node=3, r1=np.zeros(len(top)), r2=np.zeros(len(top)),
                r3=shapes[:, k], load_case=1, mode_n=k + 1, freq=float(freqs[k]),
                modal_m=1.0, modal_damp_vis=0.0, modal_damp_his=0.0,
                node_nums=np.array(top), id1="femu test", id2="", id3="", id4="", id5="",
            ),
            mode="add",
        )
    test = femu.read_test(path, model)
    np.testing.assert_allclose(test.frequencies_hz, freqs, rtol=1e-6)
    got = {(n, tuple(np.round(d, 12))): test.shapes[i] for i, (n, d) in
           enumerate(zip(test.nodes, test.directions))}
    for i, n in enumerate(top):
        np.testing.assert_allclose(got[(n, (0.0, 0.0, 1.0))], shapes[i], rtol=1e-5, atol=1e-12)


def test_errors_keep_femus_messages(tmp_path):
    with pytest.raises(femu.FemuError, match="nope.inp"):
        femu.read_model(tmp_path / "nope.inp")
    bad = tmp_path / "bad.inp"
    bad.write_text("*NODE\n1, 0, 0, 0\n*ELEMNT, TYPE=C3D8\n")
    with pytest.raises(femu.FemuError, match=r"bad.inp:3: unknown keyword \*ELEMNT"):
        femu.read_model(bad)
    with pytest.raises(ValueError, match="young, poisson and density"):
        femu.read_model(bad, young=1.0)


def test_constraints_from_a_deck_reach_python():
    m = femu.read_model(ROOT / "fixtures" / "inp" / "links.inp")
    comps = set(int(c) for c in m.dofs[:, 1])
    assert {3, 4} <= comps  # the kinematic coupling's reference rotations
    modes = m.modes(4)
    assert modes.sturm["verified"]
    d = modes.to_dict()
    assert d["sturm_verified"] and json.loads(json.dumps(d)) == d
    assert "Model(" in repr(m) and "Sturm verified" in repr(modes)


def test_the_example_script_runs(tmp_path):
    import subprocess
    import sys

    script = ROOT / "examples" / "python" / "plate_question.py"
    out = tmp_path / "demo"
    done = subprocess.run(
        [sys.executable, str(script), str(out), "--quick"], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    for name in ["table1.png", "figure1.png", "error_map.png", "report.json", "test.unv"]:
        assert (out / name).stat().st_size > 0, name
    assert "does the updated model tell the truth?" in done.stdout


def test_a_failing_progress_callback_is_raised(tmp_path):
    seen = []

    def progress(step):
        seen.append(step)
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        femu.run_demo(tmp_path / "d", quick=True, progress=progress)
    assert len(seen) == 1


@pytest.fixture(scope="module")
def plate(tmp_path_factory):
    """The quick plate study's model and test files (the test from a plate 30 % stiffer in r3)."""
    out = tmp_path_factory.mktemp("plate")
    report = femu.run_demo(out, quick=True)
    model = femu.read_model(out / "plate.inp")
    test = femu.read_test(out / "test.unv", model)
    return model, test, report


def test_correlate_against_numpy(plate):
    model, test, _ = plate
    report = femu.correlate(model, test)
    modes = model.modes(2 * len(test) + 4)
    y = test.C @ modes.vectors  # the model's modes at the sensors
    m = numpy_mac(test.shapes, y)
    for p in report["pairing"]["pairs"]:
        assert p["mac"] == pytest.approx(m[p["test"], p["model"]], rel=1e-10)
        f_model = modes.frequencies_hz[p["model"]]
        f_test = test.frequencies_hz[p["test"]]
        assert p["frequency_error"] == pytest.approx((f_model - f_test) / f_test, rel=1e-10)
    assert json.loads(json.dumps(report)) == report


def test_complex_test_modes_have_a_complex_mac(plate):
    """Complex test modes built from the plate's own modes, psi = phi_a + 0.4 i phi_b at the
    test's sensors: each pair's complex MAC is numpy's |psi^H phi|^2 / ((psi^H psi)(phi^T phi))."""
    model, test, _ = plate
    # the free plate's elastic modes (the first six are rigid-body)
    modes = model.modes(14)
    y = test.C @ modes.vectors
    re, im = y[:, [6, 8, 10]], 0.4 * y[:, [7, 9, 11]]
    directions = test.directions
    complex_test = femu.Test.from_arrays(
        model,
        test.nodes,
        directions,
        list(modes.frequencies_hz[[6, 8, 10]]),
        re,
        shapes_imaginary=im,
    )
    assert complex_test.shapes_imaginary is not None
    np.testing.assert_allclose(complex_test.shapes_imaginary, im)
    assert test.shapes_imaginary is None
    report = femu.correlate(model, complex_test, count=14)
    pairs = report["pairing"]["pairs"]
    assert [p["model"] for p in pairs] == [6, 8, 10]
    for p in pairs:
        psi = re[:, p["test"]] + 1j * im[:, p["test"]]
        phi = y[:, p["model"]]
        expected = abs(np.vdot(psi, phi)) ** 2 / (np.vdot(psi, psi).real * (phi @ phi))
        assert p["complex_mac"] == pytest.approx(expected, rel=1e-10)
    assert "complex_mac" not in femu.correlate(model, test)["pairing"]["pairs"][0]
    # the damped comparison needs the model's structural damping, which this plate has none of
    with pytest.raises(femu.FemuError, match="has no damping"):
        femu.correlate(model, complex_test, count=14, damped=True)
    with pytest.raises(femu.FemuError, match="imaginary"):
        femu.Test.from_arrays(
            model, test.nodes, directions, [1.0], re[:, :1], shapes_imaginary=im[:1, :1]
        )


def test_removal_study_points(plate):
    model, test, _ = plate
    study = femu.removal_study(model, test)
    nodes = study["nodes"]
    assert set(study["removal"]) <= set(nodes) and len(nodes) > 2
    counts = {p["nodes"] for p in study["points"]}
    # every set from all nodes down to the smallest that still has a sensor per test mode
    assert max(counts) == len(nodes)
    assert 3 * min(counts) >= len(test) > 3 * (min(counts) - 1)
    assert counts == set(range(min(counts), len(nodes) + 1))


def test_update_finds_the_stiffer_region_and_reports_each_iteration(plate):
    model, test, _ = plate
    seen = []
    sets = [f"r{i}" for i in range(10)]
    study = femu.update(model, test, sets, tuned=4, progress=seen.append)
    assert seen and all({"iteration", "objective", "theta"} <= set(it) for it in seen)
    assert study["updated_sets"] == ["R3"]
    # the test was made from a plate 30 % stiffer in r3 (with noise and the model's own mesh)
    identified = study["result"]["theta"][0]
    assert 0.2 < identified < 0.45, identified
    assert study["truth_check"]["judgement"]["verdict"] in {"agrees", "inconclusive", "disagrees"}


def test_ctrl_c_stops_a_long_call(tmp_path):
    import signal
    import threading

    started = threading.Event()
    sent = threading.Event()
    steps = []

    def progress(step):
        steps.append(step)
        started.set()
        # the first step waits until the signal is sent, so that it lands while the call runs
        # whatever the machine's load (a quick demo can otherwise finish first)
        sent.wait(10)

    def interrupt():
        started.wait()
        os.kill(os.getpid(), signal.SIGINT)
        sent.set()

    # Python's own handler, whatever the process inherited: a shell that starts a job in the
    # background without job control ignores SIGINT for it, and Python then installs none
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    t = threading.Thread(target=interrupt)
    t.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            femu.run_demo(tmp_path / "d", quick=True, progress=progress)
    finally:
        t.join()
        signal.signal(signal.SIGINT, previous)
    # stopped at a step boundary, long before the study's end
    assert 1 <= len(steps) < 6


def test_modes_report_progress_and_stop_when_asked(model):
    solved = []
    modes = model.modes(8, progress=solved.append)
    assert solved == sorted(solved) and solved[-1] >= 8 and modes.sturm["verified"]

    def stop(n):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        model.modes(8, progress=stop)
    # the hook is gone afterwards: the same solve completes
    again = model.modes(8)
    np.testing.assert_allclose(again.values, modes.values, rtol=1e-12)


def test_bricks_with_incompatible_modes(tmp_path):
    """bricks="incompatible_modes" on a Gmsh mesh builds what a C3D8I deck asks for (the brick
    checked against CalculiX in the Rust tests): the same box as a .msh and as .inp decks."""
    nx, ny, nz, (lx, ly, lz) = 6, 3, 2, (0.3, 0.06, 0.03)
    deck = box_deck(tmp_path / "c3d8.inp", nx, ny, nz)
    c3d8i = tmp_path / "c3d8i.inp"
    c3d8i.write_text(deck.read_text().replace("TYPE=C3D8,", "TYPE=C3D8I,"))
    node = lambda i, j, k: 1 + i + (nx + 1) * (j + (ny + 1) * k)
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "2",
             '2 1 "root"', '3 2 "solid"', "$EndPhysicalNames", "$Nodes",
             str((nx + 1) * (ny + 1) * (nz + 1))]
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                lines.append(f"{node(i, j, k)} {lx * i / nx!r} {ly * j / ny!r} {lz * k / nz!r}")
    quads = [[node(0, j, k), node(0, j + 1, k), node(0, j + 1, k + 1), node(0, j, k + 1)]
             for k in range(nz) for j in range(ny)]
    hexes = [[node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k),
              node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1),
              node(i, j + 1, k + 1)]
             for k in range(nz) for j in range(ny) for i in range(nx)]
    lines += ["$EndNodes", "$Elements", str(len(quads) + len(hexes))]
    e = 0
    for q in quads:
        e += 1
        lines.append(f"{e} 3 2 1 1 " + " ".join(map(str, q)))
    for h in hexes:
        e += 1
        lines.append(f"{e} 5 2 2 2 " + " ".join(map(str, h)))
    lines.append("$EndElements")
    msh = tmp_path / "box.msh"
    msh.write_text("\n".join(lines) + "\n")
    steel = dict(young=2.1e11, poisson=0.3, density=7850.0, fix=["root"])
    f = lambda m: m.modes(3).frequencies_hz
    with_modes = f(femu.read_model(msh, bricks="incompatible_modes", **steel))
    np.testing.assert_allclose(with_modes, f(femu.read_model(c3d8i)), rtol=1e-9)
    plain = f(femu.read_model(msh, **steel))
    np.testing.assert_allclose(plain, f(femu.read_model(deck)), rtol=1e-9)
    assert plain[0] > with_modes[0]
    with pytest.raises(ValueError, match="incompatible_modes"):
        femu.read_model(msh, bricks="C3D8I", **steel)


def test_a_nastran_beam_model_gives_nastrans_eigenvalues():
    # pyNastran's beam model (CBAR, CBEAM on PBARL/PBEAML, a CONM2 with inertia) and Simcenter
    # Nastran's eigenvalues from its .f06: the same model through the Python front end
    m = femu.read_model(ROOT / "fixtures" / "nastran" / "pynastran" / "beam_modes.dat")
    comps = set(int(c) for c in m.dofs[:, 1])
    assert {3, 4, 5} <= comps  # the beams' rotations
    assert m.total_mass == pytest.approx(2.610514e-2, rel=5e-7)
    nastran = [8.232777e6, 8.232777e6, 2.824056e8, 2.824056e8, 4.989076e8,
               8.021004e8, 1.733310e9, 1.733310e9, 4.874295e9, 4.874295e9]
    modes = m.modes(10)
    assert modes.sturm["verified"]
    np.testing.assert_allclose(modes.values, nastran, rtol=6e-7)


def panel_deck(path, t2, mass, nx=8, ny=6):
    """A Nastran panel clamped along x = 0: CQUAD4 in PSHELL 1 (inner half) and 2 (outer half,
    thickness `t2`), a CONM2 of `mass` at a free corner."""
    g = lambda i, j: 1 + i + (nx + 1) * j
    lines = ["SOL 103", "CEND", "SPC = 1", "BEGIN BULK", "PARAM,COUPMASS,1"]
    for j in range(ny + 1):
        for i in range(nx + 1):
            lines.append(f"GRID,{g(i, j)},,{0.6 * i / nx!r},{0.4 * j / ny!r},0.")
        lines.append(f"SPC1,1,123456,{g(0, j)}")
    for j in range(ny):
        for i in range(nx):
            pid = 1 if 2 * i < nx else 2
            lines.append(f"CQUAD4,{1000 + i + nx * j},{pid},{g(i, j)},{g(i + 1, j)},"
                         f"{g(i + 1, j + 1)},{g(i, j + 1)}")
    lines += ["PSHELL,1,1,0.003,1,,1", f"PSHELL,2,1,{t2!r},1,,1", "MAT1,1,2.1+11,,0.3,7850.",
              f"CONM2,7000,{g(nx, 0)},,{mass!r}", "ENDDATA"]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_update_finds_a_shell_thickness_and_a_conm2_mass(tmp_path):
    # the real panel's outer half 10 % thinner and its CONM2 half as heavy again, formed by femu
    # at that thickness and mass; the update reaches them through the thickness law (t:PID2)
    # and the CONM2's mass set from Python as from the CLI
    real = femu.read_model(panel_deck(tmp_path / "real.bdf", 0.9 * 0.003, 0.3))
    modes = real.modes(6)
    rows = {(int(n), int(c)): r for r, (n, c) in enumerate(real.dofs)}
    csv = ["mode,frequency_hz,node,direction,value"]
    for j, f in enumerate(modes.frequencies_hz):
        # z at every other grid off the clamp
        for node in (1 + i + 9 * k for k in range(0, 7, 2) for i in range(2, 9, 2)):
            z = float(modes.vectors[rows[(node, 2)], j])
            csv.append(f"{j + 1},{float(f)!r},{node},z,{z!r}")
    (tmp_path / "test.csv").write_text("\n".join(csv) + "\n")
    model = femu.read_model(panel_deck(tmp_path / "panel.bdf", 0.003, 0.2))
    test = femu.read_test(tmp_path / "test.csv", model)
    study = femu.update(model, test, ["t:PID1", "t:PID2", "CONM2_7000"], select="all")
    got = dict(zip(study["result"]["names"], study["result"]["theta"]))
    assert got["t:PID2"] == pytest.approx(-0.1, abs=1e-6), got
    assert got["m:CONM2_7000"] == pytest.approx(0.5, abs=1e-6), got
    assert abs(got["t:PID1"]) < 1e-6, got


def cantilever_deck(path, i2_root, i1_tip):
    """A Nastran cantilever of 24 CBARs (PBAR, no shear flexibility) in two properties with a
    CONM2 at its tip: the root half's I2 and the tip half's I1 given."""
    lines = ["SOL 103", "CEND", "SPC = 1", "BEGIN BULK", "PARAM,COUPMASS,1"]
    lines += [f"GRID,{i + 1},,{i / 24!r},0.,0." for i in range(25)]
    lines += [f"CBAR,{100 + i},{1 if 2 * i < 24 else 2},{i + 1},{i + 2},0.,1.,0." for i in range(24)]
    lines += [
        f"PBAR,1,1,6.e-4,2.e-8,{i2_root!r},5.e-8",
        f"PBAR,2,1,6.e-4,{i1_tip!r},4.5e-8,5.e-8",
        "MAT1,1,2.1e11,,0.3,7850.",
        "CONM2,900,25,,0.5",
        "SPC1,1,123456,1",
        "ENDDATA",
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_update_finds_beam_section_changes(tmp_path):
    # the real cantilever's root half 40 % stiffer in I2 and its tip half 20 % softer in I1,
    # written on its PBARs; the section parameters (EI2:PID1, EI1:PID2) find them from Python as
    # from the CLI and study files (one set-name parser)
    real = femu.read_model(cantilever_deck(tmp_path / "real.bdf", 1.4 * 4.5e-8, 0.8 * 2.0e-8))
    modes = real.modes(8)
    rows = {(int(n), int(c)): r for r, (n, c) in enumerate(real.dofs)}
    csv = ["mode,frequency_hz,node,direction,value"]
    for j, f in enumerate(modes.frequencies_hz):
        for node in range(5, 26, 4):
            for c, d in ((1, "y"), (2, "z")):
                v = float(modes.vectors[rows[(node, c)], j])
                csv.append(f"{j + 1},{float(f)!r},{node},{d},{v!r}")
    (tmp_path / "test.csv").write_text("\n".join(csv) + "\n")
    model = femu.read_model(cantilever_deck(tmp_path / "beam.bdf", 4.5e-8, 2.0e-8))
    test = femu.read_test(tmp_path / "test.csv", model)
    study = femu.update(model, test, ["EI1:PID1", "EI2:PID1", "EI1:PID2", "EI2:PID2"], select="all")
    got = dict(zip(study["result"]["names"], study["result"]["theta"]))
    assert got["EI2:PID1"] == pytest.approx(0.4, abs=1e-6), got
    assert got["EI1:PID2"] == pytest.approx(-0.2, abs=1e-6), got
    assert abs(got["EI1:PID1"]) < 1e-6 and abs(got["EI2:PID2"]) < 1e-6, got


def test_modes_written_as_a_universal_file(model, tmp_path):
    """`Model.write_modes_uff`: the box's four lowest modes written as a universal file and read
    by pyuff (an independent reader): each mode's frequency and its translations at every free DOF
    equal femu's own (the file's six digits: 1e-5 of the largest component), and the clamped nodes'
    translations are zero."""
    pyuff = pytest.importorskip("pyuff")
    modes = model.modes(4)
    path = tmp_path / "modes.unv"
    model.write_modes_uff(modes, path)
    sets = pyuff.UFF(str(path)).read_sets()
    nodes = [s for s in sets if s["type"] == 2411]
    assert len(nodes) == 1 and len(nodes[0]["node_nums"]) == len(model.node_ids)
    shapes = [s for s in sets if s["type"] == 55]
    assert len(shapes) == 4
    dofs = model.dofs
    for k, s in enumerate(shapes):
        assert s["freq"] == pytest.approx(modes.frequencies_hz[k], rel=1e-5)
        at = {int(n): (r1, r2, r3) for n, r1, r2, r3 in zip(s["node_nums"], s["r1"], s["r2"], s["r3"])}
        phi = modes.vectors[:, k]
        scale = np.abs(phi).max()
        for row, (node, comp) in enumerate(dofs):
            assert at[int(node)][comp] == pytest.approx(phi[row], abs=1e-5 * scale)
        free = {int(n) for n, _ in dofs}
        for node, values in at.items():
            if node not in free:
                assert values == (0.0, 0.0, 0.0)


def test_damped_modes_of_a_structurally_damped_box(tmp_path):
    """`modes(damped=True)`: the box's steel with `*DAMPING, STRUCTURAL=0.02` damps every element
    alike (`K_4 = 0.02 K`), so each complex mode is real (MPC 1) with the root `p = i omega sqrt(1 +
    0.02 i)` of its real mode's `omega`, computed here (frequency `Im p / 2 pi`, damping `-2 Re p /
    Im p`); undamped, the request is refused with the reason."""
    path = box_deck(tmp_path / "box.inp")
    text = path.read_text().replace("*DENSITY", "*DAMPING, STRUCTURAL=0.02\n*DENSITY")
    damped_path = tmp_path / "damped.inp"
    damped_path.write_text(text)
    modes = femu.read_model(damped_path).modes(4, damped=True)
    d = modes.to_dict()
    assert len(d["damped"]) == 4
    for mode, f in zip(d["damped"], d["frequencies_hz"]):
        p = 1j * 2 * np.pi * f * np.sqrt(1 + 0.02j)
        assert mode["eigenvalue"] == pytest.approx([p.real, p.imag], rel=1e-9)
        assert mode["damping"] == pytest.approx(-2 * p.real / p.imag, rel=1e-9)
        assert mode["mpc"] == pytest.approx(1.0, abs=1e-9)
        assert mode["frequency_hz"] == pytest.approx(p.imag / (2 * np.pi), rel=1e-9)
    with pytest.raises(femu.FemuError, match="has no damping"):
        femu.read_model(path).modes(4, damped=True)

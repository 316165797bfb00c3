"""scipy's eigsh in shift-invert mode on femu's K.mtx and M.mtx: `scipy_eigsh.py DIR COUNT`."""
import json, math, sys, time
import scipy.io, scipy.sparse.linalg as sla

d, k = sys.argv[1], int(sys.argv[2])
K = scipy.io.mmread(f"{d}/K.mtx").tocsc()
M = scipy.io.mmread(f"{d}/M.mtx").tocsc()
t = time.perf_counter()
vals = sla.eigsh(K, k=k, M=M, sigma=0.0, which="LM", return_eigenvectors=False)
dt = time.perf_counter() - t
f = sorted(math.sqrt(max(v, 0.0)) / (2 * math.pi) for v in vals)
print(json.dumps({"eigen_s": dt, "frequencies_hz": f}))

#!/usr/bin/env python3
# Experiment (docs/performance.md, "Fifth stop"): the iterations of implicit
# Euler's block-Jacobi PCG against CG preconditioned by a geometric multigrid
# V-cycle (bilinear prolongation on the grid, Galerkin coarse operators, damped
# block-Jacobi smoothing, a direct solve on the coarsest grid), on one linear
# solve dumped by a build with dump_solve.patch applied:
#   git apply tools/experiments/dump_solve.patch && cmake --build build --target wetcloth_cli
#   WETCLOTH_DUMP=300 build/wetcloth run pull-straight ... (writes /tmp/dump_A.txt, /tmp/dump_v.txt)
#   python3 tools/experiments/multigrid_solve.py [DUMP_DIR] [TOLERANCE]
# Needs numpy and scipy; not part of the build or the tests.
import numpy as np, scipy.sparse as sp, scipy.sparse.linalg as spla, sys
folder = sys.argv[1] if len(sys.argv) > 1 else '/tmp'
tol = float(sys.argv[2]) if len(sys.argv) > 2 else 1e-4  # integrator.cg_tolerance
t = np.loadtxt(f'{folder}/dump_A.txt')
hdr = open(f'{folder}/dump_v.txt').readline().split()
nu, nv = int(hdr[0]), int(hdr[1])
v = np.loadtxt(f'{folder}/dump_v.txt', skiprows=1)
n = nu * nv
N = 3 * n
A = sp.csr_matrix((t[:, 2], (t[:, 0].astype(int), t[:, 1].astype(int))), shape=(N, N))
mass = v[:, 0]; fixed = v[:, 1] > 0; nrm = v[:, 2:5]; r0 = v[:, 5:8].reshape(-1)
# S = I - n n^T per particle, 0 for fixed
blocks = []
for a in range(n):
    blocks.append(np.zeros((3, 3)) if fixed[a] else np.eye(3) - np.outer(nrm[a], nrm[a]))
S = sp.block_diag(blocks, format='csr')
# symmetric part over free rows (fixed rows are identity in A; their cols only enter the start residual)
Af = S @ A @ S
Af = 0.5 * (Af + Af.T)
Aop = (Af + (sp.identity(N) - S)).tocsr()
print(f'grid {nu}x{nv}: nnz(A)={A.nnz}, asym={abs(Af - (S@A@S)).max():.2e}, held={int((np.abs(nrm).sum(1)>0).sum())}, fixed={fixed.sum()}')
minv = np.repeat(1 / mass, 3)
def converged(r):
    rr = (r.reshape(-1, 3) ** 2).sum(1) / mass ** 2
    return np.sqrt(rr.max()) <= tol
def block_inv(M):
    M = M.tocsr()
    inv = []
    for a in range(M.shape[0] // 3):
        B = M[3 * a:3 * a + 3, 3 * a:3 * a + 3].toarray()
        inv.append(np.linalg.inv(B) if abs(np.linalg.det(B)) > 0 else np.zeros((3, 3)))
    return sp.block_diag(inv, format='csr')
def pcg(Aop, b, prec, maxit=1000):
    x = np.zeros_like(b); r = b.copy(); r = S @ r
    z = S @ prec(r); p = z.copy(); rz = r @ z
    for it in range(maxit):
        if converged(r): return it, x
        q = S @ (Aop @ p); al = rz / (p @ q)
        x += al * p; r -= al * q
        z = S @ prec(r); rz2 = r @ z; p = z + rz2 / rz * p; rz = rz2
    return maxit, x
Dinv = block_inv(Aop)
it, xj = pcg(Aop, r0, lambda r: Dinv @ r)
print('block-Jacobi PCG iterations', it)
# geometric multigrid: bilinear prolongation on the grid, Galerkin coarse operators
def prolong(nu, nv):
    cu, cv = nu // 2 + 1, nv // 2 + 1
    rows, cols, vals = [], [], []
    for j in range(nv):
        for i in range(nu):
            wi = [(i // 2, 1.0)] if i % 2 == 0 else [((i + 1) // 2, 1.0)] if i == nu - 1 else [((i - 1) // 2, .5), ((i + 1) // 2, .5)]
            wj = [(j // 2, 1.0)] if j % 2 == 0 else [((j + 1) // 2, 1.0)] if j == nv - 1 else [((j - 1) // 2, .5), ((j + 1) // 2, .5)]
            for (I, a) in wi:
                for (J, b) in wj:
                    for k in range(3):
                        rows.append(3 * (j * nu + i) + k); cols.append(3 * (J * cu + I) + k); vals.append(a * b)
    return sp.csr_matrix((vals, (rows, cols)), shape=(3 * nu * nv, 3 * cu * cv)), cu, cv
levels = []
M = Aop; Pmats = []; cu, cv = nu, nv; first = True
while cu > 7:
    P, cu2, cv2 = prolong(cu, cv)
    if first: P = S @ P; first = False
    Pmats.append(P); levels.append(M)
    M = (P.T @ M @ P).tocsr(); cu, cv = cu2, cv2
    d = M.diagonal(); M = (M + sp.diags((np.abs(d) < 1e-300).astype(float))).tocsr()
levels.append(M)
coarse = spla.splu(M.tocsc())
Dinvs = [block_inv(L) for L in levels[:-1]]
work = sum(L.nnz for L in levels) / A.nnz
print('levels', [L.shape[0] // 3 for L in levels], 'operator complexity', round(work, 2))
def vcycle(l, b, nu_s=2, w=0.6):
    if l == len(levels) - 1: return coarse.solve(b)
    L, D = levels[l], Dinvs[l]
    x = w * (D @ b)
    for _ in range(nu_s - 1): x += w * (D @ (b - L @ x))
    rc = Pmats[l].T @ (b - L @ x)
    x += Pmats[l] @ vcycle(l + 1, rc, nu_s, w)
    for _ in range(nu_s): x += w * (D @ (b - L @ x))
    return x
for nus, w in [(1, .6), (2, .6), (2, .8), (3, .6)]:
    it2, xm = pcg(Aop, r0, lambda r: vcycle(0, r, nus, w))
    # work per iteration in fine-matvec units: 1 (CG) + smoothing on each level (2 nus matvecs) + residuals
    per = 1 + sum((2 * nus + 1) * L.nnz / A.nnz for L in levels[:-1])
    print(f'MG-PCG nu={nus} w={w}: iterations {it2}, ~{per:.1f} fine matvecs each, total {it2*per:.0f} vs Jacobi {it}  |dx|={np.abs(xm-xj).max():.2e}')

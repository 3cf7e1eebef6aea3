"""The NLP functions of a multiple-shooting transcript, assembled interval by interval and
compiled to C once (cached on disk).

CasADi's own NLP functions (:attr:`Transcript.nlp` with ``expand``) are one flat
expression over all N intervals: their Hessian and Jacobian are evaluated by CasADi's
virtual machine (about 30 machine instructions per operation), and compiling them
(CasADi's ``jit``) takes minutes because the C code grows with N. Here the same functions
are built from the derivatives of *one* interval, evaluated for all intervals by
``map`` and assembled into the NLP's sparse matrices:

* ``stage(x, u, t, p, T) -> (F, L T/N, g)`` (:attr:`Transcript.stage`): the interval's
  end state, cost and path constraints; its Jacobian with respect to z = (x, u), the
  gradient of its cost, and the Hessian of its share of the Lagrangian
  lambda_f L T/N - lambda_gap . F + lambda_path . g (the gap x_{k+1} - F is linear in
  x_{k+1});
* ``terminal(x, p) -> (E, h)`` likewise.

The stage-wise NLP (gaps, initial state, path constraints, terminal constraints; see
:mod:`.transcription`) is block-sparse: the Jacobian has the blocks [-dF/dz, I] and
dg/dz per interval with their structural zeros (the pattern of CasADi's own Jacobian,
so fatrop detects the same stages), the Hessian dense blocks on the diagonal, one per
z_k. The functions carry the names and signatures of CasADi's ``nlpsol`` (``nlp``,
``nlp_f``, ``nlp_g``, ``nlp_grad_f``, ``nlp_jac_g``, ``nlp_hess_l`` with the gradient of
the Lagrangian as fatrop needs it, ``nlp_grad`` for the multipliers after a solve), so
that a library of them *is* the NLP for ``casadi.nlpsol(name, "fatrop", library)``.
The generated C holds each interval function once and a loop over the intervals, so it
compiles in seconds whatever N; the library is kept in :func:`cache_dir` under the hash
of its source, so a structure is compiled once per machine.

:func:`functions` are MX functions that also run without a compiler (CasADi's virtual
machine, slower than the flat SX functions); tests check them against CasADi's own
differentiation of :attr:`Transcript.nlp`.
"""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np

from tetherland import ccode
from tetherland.planning.transcription import Transcript

# (the compiler, its flags and the cache live in tetherland.ccode; imported here, where the
# NLP's library is built, under the names they always had)
COMPILER, FLAGS, CACHE_ENV = ccode.COMPILER, ccode.FLAGS, ccode.CACHE_ENV
available, cache_dir = ccode.available, ccode.cache_dir


def _sx_function(
    name: str, inputs: dict[str, ca.SX], outputs: list[ca.SX], sparse: int = 0
) -> ca.Function:
    """An SX function whose outputs share their common subexpressions, dense but for the
    last ``sparse`` ones (which keep their structural zeros)."""
    n = len(outputs) - sparse
    out = ca.cse([ca.densify(o) for o in outputs[:n]] + outputs[n:])
    return ca.Function(
        name, list(inputs.values()), out, list(inputs), [f"o{i}" for i in range(len(out))]
    )


def _interval_functions(tr: Transcript) -> dict[str, ca.Function]:
    """The SX functions of one interval and of the terminal node with their derivatives
    (z = (x, u); the Jacobians with their structural zeros, the Hessians dense)."""
    S, E = tr.stage, tr.terminal
    x, u = ca.SX.sym("x", tr.nx), ca.SX.sym("u", tr.nu)
    t, p, T = ca.SX.sym("t"), ca.SX.sym("p", S.size1_in(3)), ca.SX.sym("T")
    lam_f, lam_gap = ca.SX.sym("lam_f"), ca.SX.sym("lam_gap", tr.nx)
    lam_path, lam_h = ca.SX.sym("lam_path", S.size1_out(2)), ca.SX.sym("lam_h", E.size1_out(1))
    z = ca.vertcat(x, u)
    F, L, g = S(x, u, t, p, T)
    H, grad = ca.hessian(lam_f * L - ca.dot(lam_gap, F) + ca.dot(lam_path, g), z)
    E_cost, h = E(x, p)
    H_N, grad_N = ca.hessian(lam_f * E_cost + ca.dot(lam_h, h), x)
    stage = {"x": x, "u": u, "t": t, "p": p, "T": T}
    lam = {"lam_f": lam_f, "lam_gap": lam_gap, "lam_path": lam_path}
    node = {"x": x, "p": p}
    return {
        "stage_jac": _sx_function(
            "stage_jac", stage, [F, g, ca.jacobian(F, z), ca.jacobian(g, z)], sparse=2
        ),
        "stage_grad": _sx_function("stage_grad", stage, [ca.gradient(L, z)]),
        "stage_lag": _sx_function("stage_lag", {**stage, **lam}, [grad, H]),
        "terminal_jac": _sx_function("terminal_jac", node, [h, ca.jacobian(h, x)], sparse=1),
        "terminal_grad": _sx_function("terminal_grad", node, [ca.gradient(E_cost, x)]),
        "terminal_lag": _sx_function(
            "terminal_lag", {**node, "lam_f": lam_f, "lam_h": lam_h}, [grad_N, H_N]
        ),
    }


def functions(tr: Transcript) -> dict[str, ca.Function]:
    """``nlp``, ``nlp_f``, ``nlp_g``, ``nlp_grad_f``, ``nlp_jac_g``, ``nlp_hess_l`` and
    ``nlp_grad`` of the transcript, as CasADi's ``nlpsol`` names and calls them (MX
    functions of the NLP variables w, the parameters P = [p, T, x_init] and the
    multipliers)."""
    N, nx, nu = tr.nodes, tr.nx, tr.nu
    nz = nx + nu
    S, E = tr.stage, tr.terminal
    n_p, ng = S.size1_in(3), S.size1_out(2)
    fs = _interval_functions(tr)
    w, P = ca.MX.sym("x", tr.n_w), ca.MX.sym("p", n_p + 1 + nx)
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", len(tr.equality))
    p, T, x_init = P[:n_p], P[n_p], P[n_p + 1 :]
    body = ca.reshape(w[: N * nz], nz, N)  # column k: z_k = (x_k, u_k)
    X, U, x_N = body[:nx, :], body[nx:, :], w[N * nz :]
    args = (X, U, ca.DM(np.arange(N)).T * (T / N), p, T)
    X_next = ca.horzcat(X[:, 1:], x_N)

    def rows(F: ca.MX, path: ca.MX, h: ca.MX) -> ca.MX:
        """The constraints in the transcript's order: gap_0, init, [gap_k, path_k] for
        k >= 1, h."""
        gap = X_next - F
        middle = ca.vertcat(gap[:, 1:], path[:, 1:]) if ng else gap[:, 1:]
        return ca.vertcat(gap[:, 0], X[:, 0] - x_init, ca.vec(middle), h)

    F, L, path = S.map(N)(*args)
    E_cost, h = E(x_N, p)
    f, g = ca.sum2(L) + E_cost, rows(F, path, h)
    grad_f = ca.vertcat(ca.vec(fs["stage_grad"].map(N)(*args)), fs["terminal_grad"](x_N, p))
    # Jacobian: the blocks' nonzeros gathered into compressed-column order
    F_j, path_j, JF, Jg = fs["stage_jac"].map(N)(*args)
    h_j, Jh = fs["terminal_jac"](x_N, p)
    pattern, order = _jacobian_pattern(tr, fs)
    values = [ca.vec(v.nz[:]) for v in (-JF, Jg[:, nz:], Jh)] + [ca.DM.ones((N + 1) * nx)]
    jac = ca.sparsity_cast(ca.vertcat(*values)[order.tolist()], pattern)
    # Hessian of lam_f f + lam_g . g: block-diagonal in the z_k and x_N
    end = 2 * nx + (N - 1) * (nx + ng)
    mid = ca.reshape(lam_g[2 * nx : end], nx + ng, N - 1)
    lam_gap = ca.horzcat(lam_g[:nx], mid[:nx, :])
    lam_path = ca.horzcat(ca.MX.zeros(ng, 1), mid[nx:, :])  # interval 0 has no path rows
    grad_z, H = fs["stage_lag"].map(N)(*args, lam_f, lam_gap, lam_path)
    grad_N, H_N = fs["terminal_lag"](x_N, p, lam_f, lam_g[end:])
    # ... its gradient adds the identities of the gaps (on x_{k+1}) and of the initial state
    shift = ca.vertcat(ca.horzcat(lam_g[nx : 2 * nx], lam_gap[:, : N - 1]), ca.MX.zeros(nu, N))
    grad_lag = ca.vertcat(ca.vec(grad_z + shift), grad_N + lam_gap[:, N - 1])
    blocks = [ca.Sparsity.dense(nz, nz)] * N + [ca.Sparsity.dense(nx, nx)]
    hess = ca.sparsity_cast(ca.vertcat(ca.vec(H), ca.vec(H_N)), ca.diagcat(*blocks))
    # the multipliers' pass after a solve: CasADi's AD through the map (a reverse sweep)
    lag = lam_f * f + ca.dot(lam_g, g)
    xp = {"x": w, "p": P}
    xpl = {**xp, "lam_f": lam_f, "lam_g": lam_g}

    def mx(name: str, inputs: dict[str, ca.MX], outputs: dict[str, ca.MX]) -> ca.Function:
        return ca.Function(
            name, list(inputs.values()), list(outputs.values()), list(inputs), list(outputs)
        )

    return {
        "nlp": mx("nlp", xp, {"f": f, "g": g}),
        "nlp_f": mx("nlp_f", xp, {"f": f}),
        "nlp_g": mx("nlp_g", xp, {"g": g}),
        "nlp_grad_f": mx("nlp_grad_f", xp, {"grad_f_x": grad_f}),
        "nlp_jac_g": mx("nlp_jac_g", xp, {"g": rows(F_j, path_j, h_j), "jac_g_x": jac}),
        "nlp_hess_l": mx("nlp_hess_l", xpl, {"grad_gamma_x": grad_lag, "hess_gamma_x_x": hess}),
        "nlp_grad": mx(
            "nlp_grad",
            xpl,
            {
                "f": f,
                "g": g,
                "grad_gamma_x": ca.gradient(lag, w),
                "grad_gamma_p": ca.gradient(lag, P),
            },
        ),
    }


def _jacobian_pattern(
    tr: Transcript, fs: dict[str, ca.Function]
) -> tuple[ca.Sparsity, np.ndarray]:
    """The constraint Jacobian's sparsity and the permutation that puts the values
    [nonzeros of -dF/dz per interval, of dg/dz for intervals 1.., of dh/dx_N, ones (the
    identities)] into its compressed-column order."""
    N, nx, nu = tr.nodes, tr.nx, tr.nu
    nz = nx + nu
    JF, Jg = fs["stage_jac"].sparsity_out(2), fs["stage_jac"].sparsity_out(3)
    Jh = fs["terminal_jac"].sparsity_out(1)
    # row offsets of the blocks
    gap_row, path_row = np.zeros(N, dtype=int), np.zeros(N, dtype=int)
    row = 0
    for k in range(N):
        gap_row[k] = row
        row += nx
        if k == 0:
            init_row = row
            row += nx
        else:
            path_row[k] = row
            row += Jg.size1()
    term_row = row
    rows, cols = [], []

    def block(r0: int, c0: int, sp: ca.Sparsity) -> None:
        r, c = sp.get_triplet()  # in compressed-column order
        rows.append(r0 + np.asarray(r, dtype=int))
        cols.append(c0 + np.asarray(c, dtype=int))

    for k in range(N):
        block(gap_row[k], k * nz, JF)
    for k in range(1, N):
        block(path_row[k], k * nz, Jg)
    block(term_row, N * nz, Jh)
    eye = np.arange(nx)
    for k in range(N):  # gap_k: + x_{k+1}
        rows.append(gap_row[k] + eye)
        cols.append((k + 1) * nz + eye)
    rows.append(init_row + eye)  # init: + x_0
    cols.append(eye)
    r, c = np.concatenate(rows), np.concatenate(cols)
    order = np.lexsort((r, c))
    sp = ca.Sparsity.triplet(len(tr.equality), tr.n_w, r[order].tolist(), c[order].tolist())
    assert sp.nnz() == len(r), "overlapping Jacobian blocks"
    return sp, order


def library(tr: Transcript) -> Path:
    """The compiled library of :func:`functions` (built once per structure and machine,
    :func:`tetherland.ccode.library`).

    Raises
    ------
    RuntimeError
        If the C compiler is missing or fails.
    """
    return ccode.library(functions(tr).values(), "nlp", "NLP functions")

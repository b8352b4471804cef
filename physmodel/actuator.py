"""The Chen-Tan IPMC actuator: impedance Z, quasi-static actuation H, first mode G, M = H·G.

Seed 002 eqs. (10)-(16) (after Chen & Tan, IEEE/ASME T-Mech 13(5), 2008), composed from the
sub-models :mod:`~physmodel.transport` (charge dynamics), :mod:`~physmodel.electrode`
(distributed electrode resistance) and :mod:`~physmodel.beam` (mechanics):

    Z(s) = 2 x coth x / (A L)                                   [Ω]    eq. (10)
    H(s) = −L² Φ(s) X(x) / (E I (1 + r2 θ))                       [m/V]  eq. (13)
         = −(L² α0 W)/(2EI) · Kκe(γ − tanh γ)/(sγ + K tanh γ) · 2X/(1 + r2 θ)
    G(s) = ωn² / (s² + 2ξωn s + ωn²)                             [-]    eq. (15), unit DC gain
    M(s) = H(s) G(s)                                            [m/V]  eq. (16)

Sign convention of eq. (13): with α0 < 0 a positive voltage gives a positive tip displacement.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from . import beam, electrode, transport
from .model import PhysicsModel
from .numerics import line_kernels, principal_sqrt, tanh_and_gmt
from .params import STATE_FIELDS, State

UNITS = {"Z": "Ohm", "H": "m/V", "G": "1", "M": "m/V", "I": "A/V"}
DESCRIPTIONS = {
    "Z": "terminal impedance V/I",
    "H": "quasi-static actuation: tip displacement per volt without the mode",
    "G": "first bending mode (unit DC gain)",
    "M": "actuation: tip displacement per volt, H*G",
    "I": "terminal admittance I/V = 1/Z",
}


#: Fields the charge dynamics, polymer admittance and slice terms (γ, θ, A, 1/(1 + r2 θ)) depend on.
SLICE_FIELDS = ("h", "d", "K", "W", "kappa_e", "r2", "Rp")
#: ... and, with these, the electrode line (X, x coth x).
LINE_FIELDS = SLICE_FIELDS + ("r1", "L")


def _take(p, idx, fields, differ=None):
    """The rows ``idx`` of ``p``'s ``fields``; a field not in ``differ`` (the same in every set,
    rows set-major) as its first ``len(idx)`` rows, the same values without a gather."""
    if idx is None:
        return p
    # ndarray.take: the same gather as p[f][idx], without fancy indexing's set-up (~0.3 against 0.7 µs)
    if differ is None:
        return {f: p[f].take(idx, 0) for f in fields}
    return {f: p[f].take(idx, 0) if f in differ else p[f][:len(idx)] for f in fields}


def actuator_kernel(p, s, quantities=("Z", "H", "G", "M"), shared=None, differ=None) -> dict:
    """The actuator ``quantities`` at points ``s`` for parameter values ``p`` (see :class:`State`).

    Only what the quantities need is computed: G alone needs no charge dynamics or electrode
    line (:func:`~physmodel.electrode.strip_terms`), H and M no x coth x.  ``shared``: optional
    ``(line, slice)`` for ``p`` as (n, 1) columns (see :func:`shared_rows`), each None or
    ``(first, inverse)``: the electrode line is evaluated only on the rows ``line[0]`` (row r takes
    the values of ``line[0][line[1][r]]``), the slice terms only on ``slice[0]`` of those; the
    same operations on the same numbers, so the same results bit for bit.  ``differ``: with
    ``shared``, the fields that may differ between sets (default all; see :func:`shared_sets`).
    """
    out = {}
    wn = p["omega_n"]
    if "G" in quantities or "M" in quantities:
        # G = ωn²/(s² + 2ξωn s + ωn²); keep the denominator, fold ωn² into the gain below
        gden = s + 2.0 * p["xi"] * wn
        gden *= s
        gden += wn * wn
    if "G" in quantities:
        out["G"] = (wn * wn) / gden
    want_z = "Z" in quantities or "I" in quantities
    want_h = "H" in quantities or "M" in quantities
    if not (want_z or want_h):
        return out
    line, sl = shared if shared is not None else (None, None)
    pl = _take(p, None if line is None else line[0], LINE_FIELDS, differ)
    ps = _take(pl, None if sl is None else sl[0], SLICE_FIELDS, differ)
    up = (lambda a: a) if sl is None else (lambda a: a.take(sl[1], 0))          # slice rows -> line rows
    full = (lambda a: a) if line is None else (lambda a: a.take(line[1], 0))    # line rows -> all rows
    c = transport.charge_terms(s, ps["h"], ps["d"], ps["K"])
    theta = transport.polymer_admittance(ps["W"], ps["h"], ps["kappa_e"], c)
    A, frac = electrode.slice_admittance(theta, ps["r2"], ps["Rp"])
    A = up(A)
    X, xcoth = line_kernels(electrode.line_argument(A, pl["r1"], pl["L"]), want_xcoth=want_z)
    if want_z:
        Z = full(electrode.terminal_impedance(A, pl["L"], xcoth))
        if "Z" in quantities:
            out["Z"] = Z
        if "I" in quantities:
            out["I"] = 1.0 / Z
    if want_h:
        # H = −L² Φ X frac/(E I), with Φ = α0 W κe K (γ − tanh γ)/(sγ + K tanh γ)
        # (transport.moment_coupling); constants folded into one scalar multiplication.
        K, W, L = p["K"], p["W"], p["L"]
        gain = -(L * L) / (p["E"] * beam.second_moment(W, p["h"])) * (p["alpha0"] * W * p["kappa_e"] * K)
        H = up(c.gmt / c.den)
        H *= X
        H *= up(frac)
        H = full(H)
        if "H" in quantities:
            out["H"] = H * gain
        if "M" in quantities:
            H /= gden
            H *= gain * wn * wn
            out["M"] = H
    return out


def shared_rows(state: State):
    """For a batch of states (n_sets, n_T, 1) in which some sets repeat an earlier set's electrode
    line (:data:`LINE_FIELDS`) or slice (:data:`SLICE_FIELDS`) at every temperature — e.g. the
    finite-difference sets of a parameter acting only on the mode or the gain — the ``shared``
    argument of :func:`actuator_kernel` for its flat rows (set-major); None when no set does."""
    n_sets, n_T = state.T.shape[:2]
    cols = {f: getattr(state, f) for f in LINE_FIELDS}
    if n_sets < 2 or any(c.shape != (n_sets, n_T, 1) for c in cols.values()):
        return None
    return shared_sets(cols, n_sets, n_T)


def shared_sets(values, n_sets: int, n_T: int, differ=LINE_FIELDS):
    """:func:`shared_rows` for values given per field, ``n_sets·n_T`` each, set-major (any shape),
    of which only the fields ``differ`` may differ between sets (the others must be the same in
    every set: they are not compared).  Sets are compared bit for bit (their bytes)."""

    def rows(fields):
        """Each set's bytes of ``fields`` (those in ``differ``), or None when none is."""
        fs = [f for f in fields if f in differ]
        if not fs:
            return None
        b = np.concatenate([np.asarray(values[f]).reshape(n_sets, n_T, 1) for f in fs], axis=2).tobytes()
        w = len(b) // n_sets
        return [b[i * w:(i + 1) * w] for i in range(n_sets)]

    def firsts(keys, sets):
        """For each of ``sets`` the position in ``sets`` of the first one with the same key."""
        if keys is None:
            return (0,) * len(sets)
        seen: dict = {}
        return tuple(seen.setdefault(keys[i], j) for j, i in enumerate(sets))

    # a set's line is the same as another's when its slice's bytes and those of the line's own
    # fields (r1, L) are: the slice's read once
    sl = rows(SLICE_FIELDS)
    own = rows(tuple(f for f in LINE_FIELDS if f not in SLICE_FIELDS))
    line_keys = sl if own is None else own if sl is None else list(zip(sl, own, strict=True))
    line = firsts(line_keys, range(n_sets))
    return _shared_index(line, firsts(sl, sorted(set(line))), n_T)


@lru_cache(maxsize=64)
def _shared_index(line_first: tuple, slice_first: tuple, n_T: int):
    """The ``shared`` argument of :func:`actuator_kernel` from each set's first identical set
    (electrode line over all sets, slice over the line's kept sets); kept per pattern (a
    calibration repeats a few), its arrays read-only."""
    t = np.arange(n_T)

    def level(first):
        kept = sorted(set(first))
        if len(kept) == len(first):
            return None
        pos = {j: k for k, j in enumerate(kept)}
        inv = np.array([pos[j] for j in first])
        out = ((np.array(kept)[:, None] * n_T + t).ravel(), (inv[:, None] * n_T + t).ravel())
        for a in out:
            a.flags.writeable = False
        return out

    line, sl = level(line_first), level(slice_first)
    return None if line is None and sl is None else (line, sl)


class ActuatorModel(PhysicsModel):
    """Voltage-driven IPMC actuator (Chen-Tan), for one parameter set or a batch.

    >>> from physmodel import ActuatorModel, get_parameter_set
    >>> m = ActuatorModel(get_parameter_set("seed002_table3"))
    >>> r = m.frequency_response([1.0, 10.0], temperature_c=[25, 45])
    >>> r["M"].shape     # (n_sets, n_T, n_f), tip displacement per volt [m/V]
    (1, 2, 2)
    """

    kind = "actuator"
    primary_quantity = "M"

    quantities = ("Z", "H", "G", "M", "I")
    units = UNITS
    descriptions = DESCRIPTIONS

    def _kernel(self, p, s, quantities):
        return actuator_kernel(p, s, quantities)

    def evaluate_state(self, state: State, s, quantities=None) -> dict[str, np.ndarray]:
        """As :meth:`PhysicsModel.evaluate_state`; a batch that fits one chunk and whose later sets
        repeat the first one's electrode line or slice (:func:`shared_rows`) evaluates those
        terms once (the same numbers bit for bit).

        Parameters
        ----------
        state : State
            Parameter values as arrays (n_rows, n_T, 1). [SI]
        s : array_like
            1-D complex Laplace points, nonzero and finite (not checked). [1/s]
        quantities : sequence of str or None
            Names from :attr:`quantities` (default all).

        Returns
        -------
        dict of str to ndarray
            Complex arrays (n_rows, n_T, n_s) [Ω, m/V, -, m/V, A/V].
        """
        qs = self._check_quantities(quantities or self.quantities)
        s = np.asarray(s)
        n_sets, n_T = state.T.shape[:2]
        shared = shared_rows(state) if 1 < n_sets and n_sets * n_T * s.size <= self.chunk_size else None
        if shared is None:
            return super().evaluate_state(state, s, qs)
        n = n_sets * n_T
        p = {k: getattr(state, k).reshape(n, 1) for k in STATE_FIELDS}
        vals = actuator_kernel(p, s[None, :], qs, shared)
        return {q: vals[q].reshape(n_sets, n_T, s.size) for q in qs}

    def evaluate_columns(self, p, n_sets: int, n_T: int, s, quantities=None, differ=STATE_FIELDS) -> dict:
        """:meth:`evaluate_state` for a state given as flat columns ``p[field]`` (n_sets·n_T, 1),
        set-major (:meth:`~physmodel.parameter_paths.StateMap.columns`: no State to build and take
        apart per call), of which only the fields ``differ`` may differ between sets; the same
        numbers bit for bit.  The columns are only read.

        Parameters
        ----------
        p : mapping of str to ndarray
            The state's fields as columns (n_sets·n_T, 1) [SI units of each field].
        n_sets, n_T : int
            Parameter sets and temperatures the columns hold.
        s : array_like
            Laplace variable on the imaginary axis, 2πj·f [1/s].
        quantities : sequence of str or None
            The quantities to evaluate (default: the model's).
        differ : sequence of str
            The fields that may differ between sets (the others are read from the first set).

        Returns
        -------
        dict of str to ndarray
            Complex arrays (n_sets, n_T, n_s) [Ω, m/V, -, m/V, A/V].
        """
        qs = self._check_quantities(quantities or self.quantities)
        s = np.asarray(s)
        shared = (shared_sets(p, n_sets, n_T, differ) if 1 < n_sets and n_sets * n_T * s.size <= self.chunk_size
                  else None)
        if shared is None:
            state = State(**{k: p[k].reshape(n_sets, n_T, 1) for k in STATE_FIELDS})
            return super().evaluate_state(state, s, qs)
        vals = actuator_kernel(p, s[None, :], qs, shared, differ)
        return {q: vals[q].reshape(n_sets, n_T, s.size) for q in qs}

    def dc_gain(self, temperature_c) -> dict:
        """Closed-form DC limits (n_sets, n_T): ``H0 = M0`` [m/V] and ``Z0`` [Ω] (inf without leakage).

        At s = 0: θ = 0, so A = 2/Rp, x0 = L sqrt(2 r1/Rp), Φ(0) = α0 W κe (γ0 − tanh γ0)/tanh γ0.
        """
        st = self.state(temperature_c)
        g0 = st.h * principal_sqrt(st.K / st.d)
        t0, gmt0 = tanh_and_gmt(g0)
        A0 = (2.0 / st.Rp).astype(complex)
        x0 = st.L * principal_sqrt(st.r1 * A0)
        X0, xcoth0 = line_kernels(x0)
        phi0 = st.alpha0 * st.W * st.kappa_e * gmt0 / t0
        H0 = -(st.L**2) * phi0 * X0 / (st.E * st.second_moment)
        with np.errstate(divide="ignore"):
            Z0 = np.where(np.isinf(st.Rp), np.inf, np.real(2.0 * xcoth0 / (np.where(A0 == 0, 1, A0) * st.L)))
        return {"H0": np.real(H0)[..., 0], "M0": np.real(H0)[..., 0], "Z0": Z0[..., 0]}

    def reduced(self, temperature_c: float, taylor_order: int = 3, set_index: int = 0, include_mode: bool = True):
        """Seed 002 §2.2.4 finite-order model H_r·G (or H_r) as a python-control TransferFunction."""
        from .reduced import reduced_actuator

        st = self.state([temperature_c]).take(set_index, 0)
        return reduced_actuator(st, taylor_order, include_mode=include_mode)

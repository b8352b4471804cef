r"""The sensing experiment of seed 000 as a chain of documented elements around the strip, and
the chain elements registered as sensor effects of the library (:data:`EFFECTS`).

Seed 000 (Sec. II-A, Figs. 2-4) measures G(s) = I(s)/D(s): the short-circuit current i of a
cantilevered strip (18 x 6.5 x 0.21 mm, in water) per the displacement d read by a laser sensor
(Baumer OADM 20I6441/S14F) on a lightweight cup coupled to a subwoofer membrane; the strip's tip
sits in a slit cut in a wooden piece fixed to the cup; i is read through two cascaded op-amps and
both signals are sampled by a dSPACE DS1104.  What the paper's G contains besides the strip::

    G_meas(s) = sign · S(s) · B(s) · T(s) · [A(s)/A_ideal] · HP(s) · LP(s) · e^{-sτ} / L(s)

    S   short-circuit current per tip displacement (physmodel.sensor.SensorModel, quasi-static shape)
    B   tip-driven beam: the strip is clamped at the root and pinned in the slit (the slit fixes the
        tip's lateral position and lets it rotate); its own inertia (mostly added water) bends it
        away from the static shape, and the charge follows the curvature (tip_driven_beam)
    T   cup -> tip transmissibility if the wood piece rides on a compliant joint (base_excited_resonance:
        the joint's own damping; mount_resonance: damped by the surroundings, a plain pole pair);
        the paper assumes T = 1 ("nearly rigid")
    A   the two-op-amp transimpedance circuit with the strip's own impedance as source (transimpedance)
    HP, LP  an AC coupling or an anti-alias/smoothing filter in the current channel (none printed)
    e^{-sτ} relative acquisition delay current vs laser channel (pure_delay)
    L   the laser's own response: it delays the *input* channel, so it appears as a LEAD in I/D
        (laser_lag returns 1/L = 1 + sτ)

The circuit assumed (seed 000 Fig. 4 and its text, v1 = R1 i, v2 = (R3 R1/R2) i)::

    strip (Norton: i_s ∥ Z)           R1 (∥ C1)                      R3 (∥ C3)
    electrode a ── node n1 ──┬──/\/\/──┐            R2           ┌──/\/\/──┐
    electrode b ── ground    └─(−)op1──┴── v1 ──/\/\/── node n2 ──┴─(−)op2──┴── v2
                              (+)=gnd                              (+)=gnd

two inverting stages (hence v2 = +R3 R1/R2 · i).  Each op-amp is a single-pole amplifier,
1/A(s) = 1/A0 + s/ω_t (ω_t = 2π·GBW).  Node equations (solved in closed form in
:func:`transimpedance`; the tests solve them numerically)::

    n1:  i_s = v_n1/Z + (v_n1 − v1)(1/R1 + sC1),     op1: v1 = −A1 v_n1
    n2:  (v1 − v_n2)/R2 = (v_n2 − v2)(1/R3 + sC3),   op2: v2 = −A2 v_n2
    ⇒ v2/i_s = (Zf1 Zf2/R2) / [(1 + (1 + Zf1/Z)/A1) (1 + (1 + Zf2/R2)/A2)],  Zf1 = R1∥C1, Zf2 = R3∥C3

The first stage's noise gain 1 + R1/Z is what matters: the strip's Z is tens of ohms at
10-100 Hz for literature diffusivities, so 1 + R1/Z ≈ 2e4 and a 1 MHz op-amp closes the loop
near 50 Hz, in the band (the "virtual ground" fails); ``TransimpedanceChain`` in
:mod:`physmodel.sensor` models this when given ``gbw_hz``/``dc_gain`` (and ``simulate`` honours it).

Every element is a pure, vectorised function of s [rad/s] (parameters broadcast against s) with an
"off" value at which it is exactly 1.  Resonances and filters are parametrised by time constants
1/ω0 [s] so that "off" (ω0 → ∞) is the finite value 0.  :func:`chain_elements` returns the
declarations (parameters with unit, off, fit bounds, start, plausible range and source) as plain
data.  Sources are cited per parameter; where no source bounds a value the declaration says so.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field

import numpy as np

from ..errors import IPMCError, ParameterError
from .base import Effect, EffectParameter

#: First root of tan λ = tanh λ (clamped-pinned beam), and of cos λ cosh λ = −1 (clamped-free).
CLAMPED_PINNED_LAMBDA1 = 3.926602312047919
CLAMPED_FREE_LAMBDA1 = 1.8751040687119611
#: Seed 000 Fig. 4: R1 = 470 kΩ, R2 = 10 kΩ, R3 adjustable 0-50 kΩ (10 kΩ assumed; it barely matters).
SEED000_R1, SEED000_R2, SEED000_R3 = 470e3, 10e3, 10e3
#: Taylor coefficients in x² of g = (sin x − tanh x cos x)/x³, h = tanh x sin x/x², k = sech x + cos x
#: (sympy); radius π/2 in x (tanh), so for |x| < 0.25 the first term left out is < 1e-17 relative.
_G_SERIES = (2 / 3, -1 / 3, 19 / 140, -83 / 1512, 221941 / 9979200, -21587 / 2395008, 56867491 / 15567552000,
             -64533043 / 43589145600, 2606757319183 / 4344467871744000, -310604809010149 / 1277273554292736000,
             2757445630876021 / 27978373094031360000)
_H_SERIES = (1.0, -1 / 2, 71 / 360, -19 / 240, 58141 / 1814400, -15707 / 1209600, 229395011 / 43589145600,
             -18973501 / 8895744000, 2767173538681 / 3201186852864000, -3738310574519 / 10670622842880000,
             79796244279937151 / 562000363888803840000)
_K_SERIES = (2.0, -1.0, 1 / 4, -31 / 360, 11 / 320, -25261 / 1814400, 40951 / 7257600, -99680491 / 43589145600,
             3231918691 / 3487131648000, -1202439837721 / 3201186852864000, 154708098679 / 1016249794560000)
_BEAM_SERIES_LIMIT = 0.25


# ================================================================ checks
def _s(s) -> np.ndarray:
    s = np.asarray(s, dtype=complex)
    if not np.all(np.isfinite(s)):
        raise IPMCError("s must be finite complex frequencies [rad/s]")
    return s


def _par(name: str, v, lo: float = 0.0, hi: float = math.inf, lo_open: bool = False) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    bad = ~np.isfinite(a) | (a <= lo if lo_open else a < lo) | (a > hi)
    if np.any(bad):
        first = a[bad].ravel()[0] if a.ndim else a
        side = "(" if lo_open else "["
        raise ParameterError(f"{name}={first!r} must be finite and lie in {side}{lo:g}, {hi:g}]")
    return a


# ================================================================ elements (pure functions of s)
def polarity(s, sign=1.0) -> np.ndarray:
    """Sign convention of the current or displacement channel: ``sign`` ∈ {−1, +1} (off: +1). [-]"""
    a = np.asarray(sign, dtype=float)
    if not np.all(np.isin(a, (-1.0, 1.0))):
        raise ParameterError(f"polarity sign={sign!r} must be -1 or +1")
    return a * np.ones_like(_s(s))


def pure_delay(s, delay=0.0) -> np.ndarray:
    """e^{-sτ}: current channel sampled ``delay`` [s] after the laser channel (negative: before)."""
    return np.exp(-_s(s) * _par("delay", delay, -1.0, 1.0))


def first_order_lag(s, time_constant=0.0) -> np.ndarray:
    """1/(1 + sτ): a first-order low-pass in the current channel, ``time_constant`` τ [s] (off 0)."""
    return 1.0 / (1.0 + _s(s) * _par("time_constant", time_constant))


def laser_lag(s, time_constant=0.0) -> np.ndarray:
    """1 + sτ: a first-order lag τ [s] of the displacement (laser) channel seen in I/D (a lead)."""
    return 1.0 + _s(s) * _par("time_constant", time_constant)


def second_order_lowpass(s, time_constant=0.0, damping=0.7071067811865476) -> np.ndarray:
    """1/(1 + 2ζτs + τ²s²): second-order filter, τ = 1/ω0 [s] (off 0), ζ = ``damping`` [-].

    Low-frequency group delay 2ζτ; Butterworth ζ = 1/√2, Bessel (flat delay) ζ = √3/2."""
    s = _s(s)
    tau, z = _par("time_constant", time_constant), _par("damping", damping, 0.0, 10.0, lo_open=True)
    return 1.0 / (1.0 + 2.0 * z * tau * s + (tau * s) ** 2)


def highpass(s, corner_hz=0.0, order=1, damping=0.7071067811865476) -> np.ndarray:
    """AC coupling: s/(s + ωc) (order 1) or s²/(s² + 2ζωc s + ωc²) (order 2); ``corner_hz`` [Hz] (off 0)."""
    s = _s(s)
    wc = 2.0 * np.pi * _par("corner_hz", corner_hz)
    if order not in (1, 2):
        raise ParameterError(f"highpass order={order!r} must be 1 or 2")
    with np.errstate(invalid="ignore", divide="ignore"):
        if order == 1:
            h = s / (s + wc)
        else:
            z = _par("damping", damping, 0.0, 10.0, lo_open=True)
            h = s * s / (s * s + 2.0 * z * wc * s + wc * wc)
        return np.where(wc == 0.0, 1.0 + 0j, h)       # off is exactly 1, also at s = 0


def base_excited_resonance(s, time_constant=0.0, damping=0.05) -> np.ndarray:
    """Tip/cup transmissibility (2ζτs + 1)/(τ²s² + 2ζτs + 1) of a mass (wood piece + tip) on a
    spring-damper joint to the cup the laser reads: m x'' + c(x' − y') + k(x − y) = 0.

    τ = 1/ω_f = sqrt(m/k) [s] (off 0: rigid), ζ = c/(2 sqrt(k m)) [-]."""
    s = _s(s)
    tau, z = _par("time_constant", time_constant), _par("damping", damping, 0.0, 10.0, lo_open=True)
    num = 1.0 + 2.0 * z * tau * s
    return num / (num + (tau * s) ** 2)


def mount_resonance(s, time_constant=0.0, damping=0.05, relative_share=0.0) -> np.ndarray:
    """Tip/cup motion of a mount (wood piece + tip, mass m) on a joint (stiffness k) to the driven
    cup, its damping c split between the joint (relative, c_r = ν c) and the surroundings (absolute:
    the water around the piece, c_a = (1 − ν) c):

        m x'' + c_r (x' − y') + c_a x' + k (x − y) = 0
        ⇒ x/y = (1 + 2νζτs)/(1 + 2ζτs + τ²s²),   τ = sqrt(m/k) = 1/ω_f,  ζ = c/(2 sqrt(k m)).

    ν = 1 is :func:`base_excited_resonance` (the joint's own damping: a real zero at 1/(2ζτ));
    ν = 0 the plain second-order resonance, its own pole pair and no zero (Thomson & Dahleh, Theory
    of Vibration with Applications, 5th ed., §3.5 base excitation; absolute damping §3.1).
    ``time_constant`` τ [s] (off 0: rigid), ``damping`` ζ [-], ``relative_share`` ν [-]."""
    s = _s(s)
    tau, z = _par("time_constant", time_constant), _par("damping", damping, 0.0, 10.0, lo_open=True)
    nu = _par("relative_share", relative_share, 0.0, 1.0)
    return (1.0 + 2.0 * nu * z * tau * s) / (1.0 + 2.0 * z * tau * s + (tau * s) ** 2)


def tip_driven_beam(s, time_constant=0.0, damping=0.05, coupling_ratio=0.0) -> np.ndarray:
    """Current of the dynamically bent strip per current of the statically bent one, per cup motion.

    Euler-Bernoulli strip, clamped at z = 0, moment-free at z = L, its tip tied to the cup (motion
    w_c) by the slit through a spring k_c: EI w'''(L) = k_c (w(L) − w_c); ``coupling_ratio``
    ε = k_tip/k_c = 3EI/(k_c L³) (0: the tip follows the cup exactly, a clamped-pinned strip).
    Mass-proportional damping c = 2ζω1m.  With uniform electrodes the charge is ∝ ∫ curvature dz
    = w'(L) (exact for ideal electrodes; the electrode line reweights it, a second-order
    correction); the factor is w'(L)/w_c over its static value 3/(2L(1 + ε)):

        B = (2/3)(1 + ε) h(x) / (ε k(x)/3 + g(x)),   x⁴ = (βL)⁴ = −λ1⁴ (τ²s² + 2ζτs)
        g = (sin x − tanh x cos x)/x³,  h = tanh x sin x/x²,  k = sech x + cos x

    λ1 = 3.92660 (first clamped-pinned root), τ = 1/ω1 [s] (off 0; ω1 the clamped-pinned mode),
    ζ = ``damping`` [-].  Poles lie between the clamped-pinned (ε = 0) and clamped-free (ε → ∞)
    modes; whatever ε, the tip slope vanishes at x = π: an antiresonance at 0.640 ω1, i.e. 2.81 ×
    the clamped-free first mode.  B is even in x and invariant under x → jx, so any fourth root
    serves; even Taylor series of g, h, k for |x| < 0.25 (no cancellation)."""
    s = _s(s)
    tau, z = _par("time_constant", time_constant), _par("damping", damping, 0.0, 10.0, lo_open=True)
    eps = _par("coupling_ratio", coupling_ratio, 0.0, 1e6)
    y = np.asarray(-(CLAMPED_PINNED_LAMBDA1 ** 4) * ((tau * s) ** 2 + 2.0 * z * tau * s), dtype=complex)
    x = y ** 0.25                                   # principal root: |arg x| ≤ π/8 on s = jω
    if np.any(np.abs(x.imag) > 600.0):
        raise IPMCError("tip_driven_beam: frequency too far above the strip's first mode (|Im βL| > 600)")
    small = np.abs(x) < _BEAM_SERIES_LIMIT
    x2 = np.where(small, x * x, 0.0)
    g, h, k = (np.polynomial.polynomial.polyval(x2, c) for c in (_G_SERIES, _H_SERIES, _K_SERIES))
    if not np.all(small):
        xd = np.where(small, 1.0, x)
        sn, cs, th, e = np.sin(xd), np.cos(xd), np.tanh(xd), np.exp(-xd)
        g = np.where(small, g, (sn - th * cs) / xd ** 3)
        h = np.where(small, h, th * sn / (xd * xd))
        k = np.where(small, k, 2.0 * e / (1.0 + e * e) + cs)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(tau == 0.0, 1.0 + 0j, (2.0 / 3.0) * (1.0 + eps) * h / (eps * k / 3.0 + g))


def clamped_pinned_frequency_hz(E, h, W, L, rho_polymer=2000.0, rho_fluid=1000.0):
    """First clamped-pinned bending frequency [Hz] of a strip in a fluid.

    E [Pa], half-thickness h, width W, length L [m]; mass per length ρ_p·2hW plus the inviscid
    added mass π ρ_f W²/4 (Sader 1998, J. Appl. Phys. 84:64, Γ_r → 1 at high Reynolds number)."""
    EI = np.asarray(E, float) * W * (2.0 * h) ** 3 / 12.0
    m = rho_polymer * 2.0 * h * W + rho_fluid * np.pi * W * W / 4.0
    return CLAMPED_PINNED_LAMBDA1 ** 2 / L ** 2 * np.sqrt(EI / m) / (2.0 * np.pi)


def _opamp_inverse_gain(s, unity_gain_time, inverse_dc_gain):
    """1/A(s) = 1/A0 + s/ω_t for a single-pole op-amp (0 when ideal)."""
    return _par("inverse_dc_gain", inverse_dc_gain, 0.0, 1.0) + s * _par("unity_gain_time", unity_gain_time)


def transimpedance(s, source_impedance, R1=SEED000_R1, R2=SEED000_R2, R3=SEED000_R3, *, unity_gain_time=0.0,
                   inverse_dc_gain=0.0, C1=0.0, C3=0.0, unity_gain_time_2=None, inverse_dc_gain_2=None):
    """v2/i_s [V/A] of the two-stage circuit (module doc) driven by a Norton source i_s ∥ Z.

    ``source_impedance`` Z [Ω] broadcasts against s; R1, R2, R3 [Ω]; C1, C3 [F] feedback
    capacitors (not printed; off 0); op-amps: ``unity_gain_time`` 1/ω_t = 1/(2π GBW) [s] and
    ``inverse_dc_gain`` 1/A0 [-] (both 0 = ideal); stage 2 uses the same op-amp unless
    ``*_2`` are given.  Ideal limit: R3 R1/R2."""
    s = _s(s)
    Z = np.asarray(source_impedance, dtype=complex)
    if not np.all(np.isfinite(Z)) or np.any(Z == 0):
        raise IPMCError("source_impedance must be finite and non-zero [Ohm]")
    R1, R2 = _par("R1", R1, 0.0, lo_open=True), _par("R2", R2, 0.0, lo_open=True)
    R3 = _par("R3", R3, 0.0, lo_open=True)
    zf1 = R1 / (1.0 + s * R1 * _par("C1", C1))
    zf2 = R3 / (1.0 + s * R3 * _par("C3", C3))
    ia1 = _opamp_inverse_gain(s, unity_gain_time, inverse_dc_gain)
    ia2 = _opamp_inverse_gain(s, unity_gain_time if unity_gain_time_2 is None else unity_gain_time_2,
                              inverse_dc_gain if inverse_dc_gain_2 is None else inverse_dc_gain_2)
    return (zf1 * zf2 / R2) / ((1.0 + (1.0 + zf1 / Z) * ia1) * (1.0 + (1.0 + zf2 / R2) * ia2))


def transimpedance_factor(s, source_impedance, **kw) -> np.ndarray:
    """:func:`transimpedance` divided by its ideal gain R3 R1/R2 (1 when ideal). [-]"""
    R1, R2, R3 = kw.get("R1", SEED000_R1), kw.get("R2", SEED000_R2), kw.get("R3", SEED000_R3)
    return transimpedance(s, source_impedance, **kw) / (np.asarray(R3) * np.asarray(R1) / np.asarray(R2))


# ================================================================ declarations
@dataclass(frozen=True)
class ChainParameter:
    """One parameter of a chain element (SI ``unit``).

    ``off``: value at which the element is exactly 1; ``lower``/``upper``: fit bounds (wide, they
    bound what is physically possible); ``start``: a moderate "on" value; ``plausible``: the range
    the cited ``source`` supports for seed 000's set-up (None: nothing printed bounds it)."""

    name: str
    unit: str
    off: float
    lower: float
    upper: float
    start: float
    plausible: tuple | None
    source: str
    doc: str = ""
    values: tuple | None = None      # discrete parameters: the allowed values

    def __post_init__(self):
        if not (self.lower <= self.off <= self.upper and self.lower <= self.start <= self.upper):
            raise ParameterError(f"chain parameter {self.name}: off={self.off} and start={self.start} must lie "
                                 f"in [{self.lower}, {self.upper}]")


@dataclass(frozen=True)
class ChainElement:
    """A chain element: where it acts (``channel``), its parameters and its response.

    ``response(s, values, source_impedance=None)`` returns the multiplicative factor on I/D;
    ``fixed``: constants it uses (e.g. the printed resistors)."""

    name: str
    title: str
    channel: str
    description: str
    source: str
    parameters: tuple
    response: Callable = field(repr=False, compare=False)
    needs_source_impedance: bool = False
    fixed: Mapping = field(default_factory=dict)

    @property
    def off(self) -> dict:
        return {p.name: p.off for p in self.parameters}

    @property
    def start(self) -> dict:
        return {p.name: p.start for p in self.parameters}

    def factor(self, s, values: Mapping[str, float] | None = None, source_impedance=None) -> np.ndarray:
        """The element's factor at s [rad/s]; missing parameters are off."""
        v = self.off
        for k, x in (values or {}).items():
            if k not in v:
                raise ParameterError(f"chain element {self.name!r} has no parameter {k!r}; expected {list(v)}")
            v[k] = x
        if self.needs_source_impedance and source_impedance is None:
            raise IPMCError(f"chain element {self.name!r} needs the strip's impedance (source_impedance) [Ohm]")
        return self.response(s, v, source_impedance)

    def to_dict(self) -> dict:
        """Plain data: strings, numbers, lists, and the ``response`` callable."""
        return {"name": self.name, "title": self.title, "channel": self.channel, "description": self.description,
                "source": self.source, "needs_source_impedance": self.needs_source_impedance,
                "fixed": dict(self.fixed), "parameters": [asdict(p) for p in self.parameters],
                "response": self.response}


def _P(*a, **k):
    return ChainParameter(*a, **k)


_OPAMPS = ("single-pole op-amp 1/A = 1/A0 + s/ω_t (Franco, Design with Operational Amplifiers, 4th ed., ch. 6); "
           "GBW: µA741 1 MHz (TI SLOS094), LM324 1.2 MHz (TI SLOS066), TL071 3 MHz (TI SLOS080); "
           "A0: µA741 2e5 typ, 2e4 min (TI SLOS094)")
_ZETA_BEAM = ("water alone: Sader 1998 (Γ_i ≈ 0.04 at Re ≈ 5e3 for a 6.5 mm strip, ζ ≈ 0.02); an IPMC strip "
              "in water: seed 002 Table 2, ξ = 0.18 (first mode, 12 Hz)")
_ELEMENTS = (
    ChainElement(
        "polarity", "sign convention", "current or displacement",
        "Which electrode is on the op-amp's input and which way the laser counts: ±1 on I/D.  Confounded "
        "with the sign of the sensing coupling a0 (not printed), so one sign is free, not two.",
        "seed 000 Fig. 4 (two inverting stages: v2 = +R3R1/R2 i) and Sec. II-B (no sign convention printed)",
        (_P("sign", "1", 1.0, -1.0, 1.0, -1.0, None, "not printed", "±1", values=(-1.0, 1.0)),),
        lambda s, v, Z: polarity(s, v["sign"])),
    ChainElement(
        "acquisition_delay", "relative acquisition delay", "current",
        "The current sampled τ after the laser reading: e^{-sτ}.  A delay common to both channels cancels "
        "in I/D; only the channel skew (µs on a multiplexed ADC) or a sample of offset between tasks remains.",
        "dSPACE DS1104 (one multiplexed 16-bit ADC, ~2 µs per channel, and four 12-bit ADCs; hardware "
        "reference, not re-verified here); issue 16: card ≲ 1 ms",
        (_P("delay", "s", 0.0, -5e-3, 1e-2, 1e-3, (-1e-3, 1e-3),
            "DS1104 channel skew µs; one sample at ≥ 1 kHz ≤ 1 ms; more needs a filter (second_order_lowpass)"),),
        lambda s, v, Z: pure_delay(s, v["delay"])),
    ChainElement(
        "laser_lag", "laser sensor response", "displacement",
        "The laser reports the cup's position with a first-order lag τ; it delays the INPUT of I/D, so "
        "I/D gains a lead 1 + sτ.  It cannot explain a lag in the printed model.",
        "Baumer OADM 20I6x41 operating manual (BA_OADM20I6_21I6): response time T1 = 0.9 ms",
        (_P("time_constant", "s", 0.0, 0.0, 5e-3, 4e-4, (0.0, 0.9e-3), "datasheet response time 0.9 ms"),),
        lambda s, v, Z: laser_lag(s, v["time_constant"])),
    ChainElement(
        "current_lag", "first-order low-pass in the current channel", "current",
        "An RC low-pass (anti-alias or smoothing) 1/(1 + sτ) after the circuit; none is printed.",
        "seed 000 Sec. II-A (no filter printed)",
        (_P("time_constant", "s", 0.0, 0.0, 2e-2, 1e-3, None, "not printed; a fitted value names the filter needed"),),
        lambda s, v, Z: first_order_lag(s, v["time_constant"])),
    ChainElement(
        "current_lowpass2", "second-order low-pass in the current channel", "current",
        "A second-order filter 1/(1 + 2ζτs + τ²s²) (Butterworth ζ = 0.71, Bessel 0.87); its low-frequency "
        "group delay 2ζτ is how a delay beyond the card's ≲ 1 ms would have to arise.  None is printed.",
        "seed 000 Sec. II-A (no filter printed); Bessel/Butterworth: Zverev, Handbook of Filter Synthesis (1967)",
        (_P("time_constant", "s", 0.0, 0.0, 2e-2, 1.5e-3, None, "not printed; 1/ω0"),
         _P("damping", "1", 0.7071067811865476, 0.05, 3.0, 0.7071067811865476, (0.5, 1.0),
            "usual filter alignments (Chebyshev .. Bessel)")),
        lambda s, v, Z: second_order_lowpass(s, v["time_constant"], v["damping"])),
    ChainElement(
        "ac_coupling", "AC coupling (first-order high-pass)", "current",
        "A coupling capacitor or DC-removal filter s/(s + ωc) in the current channel; the printed circuit "
        "is DC-coupled.", "seed 000 Fig. 4 (DC-coupled as printed)",
        (_P("corner_hz", "Hz", 0.0, 0.0, 100.0, 10.0, None, "not printed (0 for the printed circuit)"),),
        lambda s, v, Z: highpass(s, v["corner_hz"], 1)),
    ChainElement(
        "ac_coupling2", "second-order high-pass", "current",
        "s²/(s² + 2ζωc s + ωc²): a second-order DC-removal filter; none is printed.",
        "seed 000 Fig. 4 (DC-coupled as printed)",
        (_P("corner_hz", "Hz", 0.0, 0.0, 100.0, 10.0, None, "not printed"),
         _P("damping", "1", 0.7071067811865476, 0.05, 3.0, 0.7071067811865476, (0.5, 1.0), "filter alignments")),
        lambda s, v, Z: highpass(s, v["corner_hz"], 2, v["damping"])),
    ChainElement(
        "fixture_joint", "base-excited fixture resonance (cup → tip)", "displacement",
        "The wood piece holding the tip rides on a compliant joint to the cup the laser reads: tip/cup = "
        "(1 + 2ζτs)/(1 + 2ζτs + τ²s²), τ = 1/ω_f.  The paper assumes a rigid coupling (τ = 0).",
        "seed 000 Sec. II-A, Fig. 3 ('nearly rigid'); cone break-up of subwoofer drivers ≳ several hundred Hz "
        "(Beranek & Mellow, Acoustics: Sound Fields and Transducers, 2012)",
        (_P("time_constant", "s", 0.0, 0.0, 1.0 / (2 * math.pi * 20.0), 1.0 / (2 * math.pi * 150.0),
            (0.0, 1.0 / (2 * math.pi * 200.0)), "rigid as the paper assumes, or a joint resonance above ~200 Hz"),
         _P("damping", "1", 0.05, 0.005, 1.0, 0.1, None, "joint damping, not printed")),
        lambda s, v, Z: base_excited_resonance(s, v["time_constant"], v["damping"])),
    ChainElement(
        "mount_resonance", "mount resonance (second-order mechanical element, cup → tip)", "displacement",
        "The piece holding the tip (mass m) rides on a joint of stiffness k to the cup the laser reads and is "
        "damped by its surroundings (water), not by the joint: tip/cup = 1/(1 + 2ζτs + τ²s²), τ = 1/ω_f — its "
        "own pole pair and no zero (mount_resonance with relative share ν = 0; ν = 1 is fixture_joint).  The "
        "paper assumes a rigid coupling (τ = 0).",
        "Thomson & Dahleh, Theory of Vibration with Applications (1998) §3.1, §3.5 (base excitation, absolute "
        "vs relative damping); seed 000 Sec. II-A, Fig. 3 ('nearly rigid')",
        (_P("time_constant", "s", 0.0, 0.0, 1.0 / (2 * math.pi * 10.0), 1.0 / (2 * math.pi * 150.0),
            (0.0, 1.0 / (2 * math.pi * 200.0)), "rigid as the paper assumes, or a mount resonance above ~200 Hz"),
         _P("damping", "1", 0.05, 0.005, 1.0, 0.1, None, "mount damping (to the surroundings), not printed")),
        lambda s, v, Z: mount_resonance(s, v["time_constant"], v["damping"], 0.0)),
    ChainElement(
        "tip_driven_beam", "tip-driven strip dynamics (clamped-pinned, water added mass)", "mechanical",
        "The strip's own inertia, mostly added water (π ρ_f W²/4 per length, 12x the strip's mass for seed 000), "
        "bends it away from the static shape: antiresonance at 0.64 ω1 and resonance at the first "
        "clamped-pinned mode ω1 = 1/τ, lower if the slit holds the tip through a spring (ε > 0) "
        "(tip_driven_beam).  Seed 000 geometry: f1 ≈ 49 Hz·sqrt(E/0.3 GPa).",
        "clamped-pinned λ1 = 3.9266 (Blevins, Formulas for Natural Frequency and Mode Shape, Table 8-1); "
        "added mass Sader 1998; E ≈ 0.1-0.6 GPa (physics.md §8) -> f1 ≈ 28-69 Hz",
        (_P("time_constant", "s", 0.0, 0.0, 1.0 / (2 * math.pi * 10.0), 1.0 / (2 * math.pi * 50.0),
            (1.0 / (2 * math.pi * 89.0), 1.0 / (2 * math.pi * 28.0)), "E 0.1-1 GPa with water added mass"),
         _P("damping", "1", 0.05, 0.005, 1.0, 0.1, (0.02, 0.3), _ZETA_BEAM),
         _P("coupling_ratio", "1", 0.0, 0.0, 10.0, 0.05, (0.0, 0.1),
            "k_tip/k_slit; seed 000 Sec. II-A: the strip 'presents little resistance' to the wood piece")),
        lambda s, v, Z: tip_driven_beam(s, v["time_constant"], v["damping"], v["coupling_ratio"])),
    ChainElement(
        "transimpedance", "two-op-amp transimpedance circuit with the strip as source", "current",
        "v2/i_s of seed 000's circuit with finite op-amp gain and the strip's impedance Z as source, over "
        "its ideal gain R3R1/R2: the first stage closes its loop at ≈ ω_t|Z|/R1 (module doc).",
        "seed 000 Fig. 4 (R1 = 470 kΩ, R2 = 10 kΩ, R3 0-50 kΩ); " + _OPAMPS + "; photodiode-amplifier noise "
        "gain 1 + R1/Z: Graeme, Photodiode Amplifiers (1996), ch. 2",
        (_P("unity_gain_time", "s", 0.0, 0.0, 1.0 / (2 * math.pi * 1e4), 1.0 / (2 * math.pi * 1e6),
            (1.0 / (2 * math.pi * 1e7), 1.0 / (2 * math.pi * 5e5)), "1/(2π GBW), GBW 0.5-10 MHz"),
         _P("inverse_dc_gain", "1", 0.0, 0.0, 1e-3, 5e-6, (5e-6, 5e-5), "1/A0, A0 2e4-2e5"),
         _P("feedback_capacitance", "F", 0.0, 0.0, 1e-6, 1e-9, None, "C1 ∥ R1, not printed")),
        lambda s, v, Z: transimpedance_factor(s, Z, unity_gain_time=v["unity_gain_time"],
                                              inverse_dc_gain=v["inverse_dc_gain"], C1=v["feedback_capacitance"]),
        needs_source_impedance=True, fixed={"R1": SEED000_R1, "R2": SEED000_R2, "R3": SEED000_R3}),
)

ELEMENTS: dict[str, ChainElement] = {e.name: e for e in _ELEMENTS}


def get_element(name: str) -> ChainElement:
    if name not in ELEMENTS:
        raise ParameterError(f"unknown sensing-chain element {name!r}; expected one of {sorted(ELEMENTS)}")
    return ELEMENTS[name]


def chain_elements() -> list[dict]:
    """The element declarations as plain data (see :meth:`ChainElement.to_dict`)."""
    return [e.to_dict() for e in _ELEMENTS]


def chain_response(s, settings: Mapping[str, Mapping[str, float]], source_impedance=None) -> np.ndarray:
    """Product of the elements in ``settings`` ({element: {parameter: value}}; missing = off) at s [rad/s]."""
    s = _s(s)
    out = np.ones_like(s)
    for name, vals in settings.items():
        out = out * get_element(name).factor(s, vals, source_impedance)
    return out


# ================================================================ as library effects
#: Elements registered as sensor effects (kinds ("sensor",), quantity "S"; parameters, bounds and
#: sources from the declarations above).  Not registered, because the library already has them:
#: ``acquisition_delay`` (``time_delay``: e^{-sτ}, τ in [0, 50 ms]), ``current_lag`` and real-pole
#: ``current_lowpass2`` (``amplifier_bandwidth``: two real poles); ``polarity`` is the sign of a0,
#: not an effect; ``ac_coupling2`` has no source beyond ``ac_coupling``.
REGISTERED = ("laser_lag", "ac_coupling", "fixture_joint", "mount_resonance", "tip_driven_beam", "transimpedance")
#: Sourced ranges of the parameters of library effects that model seed 000's chain (``time_delay``
#: and ``amplifier_bandwidth`` included): {"effect.param": (lower, upper, source)}.
PLAUSIBLE = {f"{n}.{p.name}": (p.plausible[0], p.plausible[1], p.source)
             for n in REGISTERED for p in ELEMENTS[n].parameters if p.plausible is not None}
PLAUSIBLE["time_delay.delay"] = (0.0, 1e-3, ELEMENTS["acquisition_delay"].source)


def _strip_impedance(ctx) -> np.ndarray:
    """The strip's terminal impedance Z [Ω] at the effect context's points (the Norton source's)."""
    if "Z" in ctx.base:
        return ctx.base["Z"]
    from .. import electrode
    from ..params import STATE_FIELDS

    p = {k: getattr(ctx.st, k) for k in STATE_FIELDS}
    t = electrode.strip_terms(p, ctx.s_kernel, want_xcoth=True)
    return electrode.terminal_impedance(t.A, p["L"], t.xcoth)


def _as_effect(el: ChainElement) -> Effect:
    pars = []
    for p in el.parameters:
        typical = p.start if p.start != p.off else p.off + 0.5 * (p.upper - p.off)
        rng = f"; sourced range [{p.plausible[0]:.3g}, {p.plausible[1]:.3g}]" if p.plausible else ""
        pars.append(EffectParameter(p.name, p.unit, p.off, p.lower, p.upper, typical, f"{p.doc or p.name}{rng} "
                                    f"({p.source})"))
    switch = "time_constant" if el.name in ("fixture_joint", "mount_resonance", "tip_driven_beam") else None

    def apply(q, ctx, v, _el=el):
        Z = _strip_impedance(ctx) if _el.needs_source_impedance else None
        return _el.response(ctx.s, v, Z)

    return Effect(el.name, el.title, el.description, el.source, "response", tuple(pars), kinds=("sensor",),
                  quantities=("S",), apply=apply, switch=switch,
                  bounds_doc="the element's fit bounds (physical limits); sourced ranges in "
                             "physmodel.effects.sensing.PLAUSIBLE")


EFFECTS = [_as_effect(ELEMENTS[n]) for n in REGISTERED]


__all__ = ["CLAMPED_PINNED_LAMBDA1", "EFFECTS", "ELEMENTS", "PLAUSIBLE", "REGISTERED", "SEED000_R1", "SEED000_R2",
           "SEED000_R3", "ChainElement", "ChainParameter", "base_excited_resonance", "chain_elements",
           "chain_response", "clamped_pinned_frequency_hz", "first_order_lag", "get_element", "highpass",
           "laser_lag", "mount_resonance", "polarity", "pure_delay", "second_order_lowpass", "tip_driven_beam", "transimpedance",
           "transimpedance_factor"]

"""Known scheduled model and noisy-sweep helper shared by the surrogate tests."""

import numpy as np

from surrogate import Scaling

# A known scheduled model (zpk form, 2 zeros, 3 poles, quadratic in T) whose zero pair is
# non-minimum phase, real below ~34 °C and complex above (the discriminant β1² − 4β2 changes
# sign): zeros at s̃ = 0.1 and 0.5 at 19 °C, 0.25 ± 0.1j at 37 °C and 0.3 ± 0.4j at 55 °C.
TRUE_SCALING = Scaling(omega_ref_rad_s=2 * np.pi * 3.0, gain_ref=2.0,
                       temperature_center_c=37.0, temperature_scale_c=18.0)
TRUE_THETA = np.array([
    [0.18, 0.05, 0.0],                # k (the numerator at s̃ = 0)
    [-6.9, 4.8, -0.3],                # zb1_0 (negative: right-half-plane zeros)
    [13.8, -8.0, -1.8],               # zb2_0
    [np.log(0.4), -0.1, 0.02],        # log_a1_0
    [0.0, -0.15, 0.0],                # log_a0_0
    [np.log(0.3), 0.1, 0.0],          # log_c
]).ravel()
FIT_TEMPS = [19.0, 25.0, 31.0, 37.0, 43.0, 49.0, 55.0]


def noisy_sweep(model, temps, f1, mag_db=0.1, ph_deg=0.6, seed=3):
    f = np.tile(f1, len(temps))
    t = np.repeat(np.asarray(temps, float), f1.size)
    h = model.frequency_response(f, t)
    rng = np.random.default_rng(seed)
    noise = rng.normal(size=f.size) * mag_db * np.log(10) / 20 + 1j * np.deg2rad(rng.normal(size=f.size) * ph_deg)
    return f, t, h * np.exp(noise), np.full(f.size, mag_db), np.full(f.size, ph_deg)

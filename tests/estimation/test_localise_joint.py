"""Where a gap sits in a joint record (issue 27, review: the "where" of a joint gap was pooled).

``localise`` of a stacked record (M and Z of one strip, :func:`physmodel.estimation.joint.joint_data`)
localises each quantity's lines in its own bands and names the quantity; the oracle is the χ²
tail of the planted lines' residuals computed here by hand, and the Bonferroni count over every
block's cells."""

import math

import numpy as np
from scipy.stats import chi2

from physmodel.data.sweep import FrequencySweep
from physmodel.estimation.diagnosis import worst_cells
from physmodel.estimation.joint import joint_data
from physmodel.estimation.signatures import localise

T = np.repeat([20.0, 40.0], 12)


def _sweep(fmin, fmax, unit_in, unit_out, name_out, name_in="voltage"):
    f = np.tile(np.geomspace(fmin, fmax, 12), 2)
    return FrequencySweep(T, f, np.ones(f.size, complex) * (1 + 0.5j), np.full(f.size, 0.1), np.full(f.size, 0.5),
                          name_in, unit_in, name_out, unit_out)


def test_a_gap_in_z_lines_is_said_as_z_s_with_the_count_over_both_blocks():
    m = _sweep(0.1, 10.0, "V", "mm", "displacement")
    z = _sweep(1.0, 1000.0, "A", "V", "voltage", "current")
    jd = joint_data([m, z], "actuator", ("M", "Z"))
    st = jd.stacked
    N = st.frequency_hz.size
    assert N == 48
    r = np.random.default_rng(1).normal(size=2 * N) * 0.3
    # the planted gap: Z's magnitude at 40 °C, its top quarter-decade band (lines 24 + 12 + 9..11)
    hit = np.arange(24 + 12 + 9, 24 + 12 + 12)
    r[hit] += 6.0
    rows = localise(st, r, 0.05)
    assert {x["quantity"] for x in rows} == {"M", "Z"}
    flagged = [x for x in rows if x["flagged"] and x["temperature_c"] is not None]
    assert flagged and all(x["quantity"] == "Z" and x["part"] == "magnitude" and x["temperature_c"] == 40.0
                           for x in flagged)
    top = min(flagged, key=lambda x: x["p_value"])
    # Z's own bands: its top band ends at 1000 Hz, not at a band shared with M's lines
    assert math.isclose(top["band_hz"][1], 1000.0, rel_tol=1e-9)
    lz = np.log10(z.frequency_hz[:12])
    edges = np.linspace(lz.min(), lz.max() + 1e-12, 5)
    in_band = 24 + 12 + np.flatnonzero(np.log10(z.frequency_hz[:12]) >= edges[3])
    assert top["n"] == in_band.size
    assert top["p_value"] == chi2.sf(float(np.sum(r[in_band] ** 2)), in_band.size)
    cells = 4 * 2 * 2 * 2          # bands × temperatures × parts, each of the two blocks
    assert top["flagged"] == (top["p_value"] < 0.05 / cells)
    assert worst_cells(rows).startswith("Z ")


def test_one_quantity_rows_name_no_quantity():
    m = _sweep(0.1, 10.0, "V", "mm", "displacement")
    r = np.random.default_rng(2).normal(size=2 * m.frequency_hz.size)
    rows = localise(m, r, 0.05)
    assert rows and all("quantity" not in x for x in rows)
    assert len([x for x in rows if x["temperature_c"] is not None]) == 4 * 2 * 2

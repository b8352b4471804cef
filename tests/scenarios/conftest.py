"""Fixtures shared by the scenario tests."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def second_recommended_record(monkeypatch):
    """The next-measurement recommendation given a second record (1-9 Hz at the record's 35 °C, a
    record no search chose: added so that the scenario step's handling of two records is checked on
    the fast bundled demo), with ``together`` built as the search builds it for a plan not checked
    by refits (``next_measurement_plan.RecordPair.together``)."""
    from dataclasses import replace

    from physmodel.estimation.diagnosis import Diagnosis
    from physmodel.estimation.next_measurement_plan import RecordPair

    real = Diagnosis.recommend_next_measurement

    def with_second(self, **kw):
        nm = real(self, **kw)
        r = nm.recommended
        f = np.arange(1.0, 10.0)
        second = replace(r, band_hz=(1.0, 9.0), temperatures_c=(35.0,), level=1.0, n_lines=f.size, frequencies_hz=f,
                         line_temperatures_c=np.full(f.size, 35.0), line_frequencies_hz=f)
        nm.also = [second]
        nm.together = RecordPair(second, r.separation, dict(r.separation_by_pair)).together()
        return nm

    monkeypatch.setattr(Diagnosis, "recommend_next_measurement", with_second)

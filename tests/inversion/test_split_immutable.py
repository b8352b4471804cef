"""An InverseSplit caches the plans built from it, so its arrays cannot change under them."""

import numpy as np
import pytest

from inversion import invert, split_inverse

DEN = [1.0, 3.0, 2.0]
NUM = [1.0, -1.0, 4.0]            # a right-half-plane zero pair: stable and anticausal parts both present


def test_split_arrays_are_read_only_copies_and_plans_stay_valid():
    num = np.array(NUM)
    sp = split_inverse((num, np.array(DEN)))
    arrays = {k: v for k, v in vars(sp).items() if isinstance(v, np.ndarray)}
    assert arrays and all(not v.flags.writeable for v in arrays.values())
    for v in arrays.values():
        if v.size:
            with pytest.raises(ValueError):
                v[(0,) * v.ndim] = 1.0
    assert not any(np.shares_memory(v, num) for v in arrays.values())     # the caller's array stays writable
    assert num.flags.writeable
    u = np.sin(2 * np.pi * np.arange(2000) * 1e-3)
    a = invert(sp, 1e-3, u, preview=0.5).output
    b = invert(sp, 1e-3, u, preview=0.5).output    # from the cached plan
    np.testing.assert_array_equal(a, b)

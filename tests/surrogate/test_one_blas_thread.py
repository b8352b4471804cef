"""The fits' BLAS limit (physmodel.numerics.one_blas_thread) holds inside, nested calls included, and
is lifted afterwards.  Oracle: threadpoolctl's own report of the loaded BLAS pools."""

from threadpoolctl import threadpool_info, threadpool_limits

from physmodel.numerics import one_blas_thread


def _blas_threads():
    return sorted(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")


def test_limit_holds_inside_nested_calls_and_is_lifted_after():
    with threadpool_limits(limits=2, user_api="blas"):      # whatever the environment says
        _check()


def _check():
    before = _blas_threads()
    assert before and all(n == 2 for n in before)

    @one_blas_thread
    def inner():
        return _blas_threads()

    @one_blas_thread
    def outer():
        return _blas_threads(), inner(), _blas_threads()

    first, nested, after_nested = outer()
    assert first == nested == after_nested == [1] * len(before)
    assert _blas_threads() == before
    assert inner() == [1] * len(before)          # a second, un-nested call sets it again
    assert _blas_threads() == before

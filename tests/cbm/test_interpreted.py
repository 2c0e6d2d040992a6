"""The interpreted path (``cbm.engine.interpreted``: every kernel's plain Python function, nothing
compiled) gives the compiled path's pairs, counts and transform on the stored reference cases of
``test_match_reference`` that a first frame may have (up to 60 objects per agent)."""
import threading

import numpy as np
import pytest

from cbm.engine.interpreted import COMPILE_LOCK as LOCK
from cbm.engine.interpreted import interpreted

from .match_reference import cases, outcome

SMALL_CASES = [case for case in cases() if max(len(case[1]), len(case[2])) <= 60]


@pytest.mark.parametrize("case", SMALL_CASES, ids=[case[0] for case in SMALL_CASES])
def test_the_interpreted_path_gives_the_compiled_results(case):
    name, ego, cav, init, variant = case
    compiled = outcome(ego, cav, init, variant)
    with interpreted():
        plain = outcome(ego, cav, init, variant)
    for key, value in compiled.items():
        np.testing.assert_array_equal(plain[key], value, err_msg=f"{name}: {key}")


def test_the_kernels_are_restored_after_the_block():
    from cbm.engine import context
    kernel = context._fill_context
    with interpreted():
        assert context._fill_context is kernel.py_func
    assert context._fill_context is kernel and not LOCK._is_owned()


def test_a_kernel_compiles_only_outside_an_interpreted_block():
    from cbm.engine import context
    from cbm.warmup import VARIANTS, warm_up
    kernel = context._fill_context
    with interpreted():
        pass
    warm_up(VARIANTS[:1])
    asked, done = threading.Event(), threading.Event()

    def compile_again():
        asked.set()
        kernel.compile(kernel.signatures[0])
        done.set()

    with interpreted():
        threading.Thread(target=compile_again, daemon=True).start()
        assert asked.wait(60)
        assert not done.wait(0.5)
    assert done.wait(60)

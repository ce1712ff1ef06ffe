"""What ``strata_rt.render`` says besides the image: what ``strata render``
prints as ``warning:`` lines, raised as Python warnings in the same words,
and Ctrl-C, which ends a render at the end of a pass."""

import _thread
import signal
import threading
import time
import warnings

import numpy as np
import pytest

import helpers
import strata_rt

SEED = str(helpers.REPO / "scenes" / "seed.toml")
LIGHT = '[[lights]]\ntype = "point"\nposition = [0.0, 0.0, 5.0]\nintensity = [1.0, 1.0, 1.0]\n'


def quietly(*args, **kwargs):
    """`render`, failing on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return strata_rt.render(*args, **kwargs)


def test_a_scene_without_light_warns(tmp_path):
    dark = tmp_path / "dark.toml"
    dark.write_text("[render]\nwidth = 8\nheight = 6\n[[objects]]\nsphere = { radius = 1.0 }\n")
    with pytest.warns(UserWarning, match="no lights and no emissive materials"):
        image = strata_rt.render(str(dark))
    assert image.shape == (6, 8, 3)
    lit = tmp_path / "lit.toml"
    lit.write_text(dark.read_text() + LIGHT)
    quietly(str(lit))


def test_more_passes_than_samples_warn_and_change_no_pixel():
    small = {"width": 16, "height": 12, "spp": 4}
    with pytest.warns(UserWarning, match=r"--passes 9: only 4 samples per pixel .* so 4 passes"):
        image = strata_rt.render(SEED, passes=9, **small)
    assert np.array_equal(image, quietly(SEED, passes=4, **small))


def test_a_mesh_read_leniently_warns_naming_its_line(tmp_path):
    (tmp_path / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl\nf 1 2 3\n")
    scene = tmp_path / "s.toml"
    scene.write_text('[render]\nwidth = 8\nheight = 6\n[[objects]]\nmesh = "tri.obj"\n' + LIGHT)
    with pytest.warns(UserWarning, match=r"tri\.obj: line 4: usemtl without a material name"):
        strata_rt.render(str(scene))


def test_ctrl_c_ends_a_render_at_a_pass_end():
    # 200,000 one-sample passes: about 0.7 ms each on one thread here, so
    # the whole render takes minutes; a machine many times faster or slower
    # still cannot end it before the interrupt (a quarter of a second in),
    # nor take ten seconds to stop if each pass's end checks for it. No
    # other render is timed to choose the moment.
    settings = {"width": 48, "height": 32, "spp": 200_000, "passes": 200_000, "threads": 1}
    # Python's own Ctrl-C handler, whatever this process inherited: a test
    # run started in the background by a script inherits SIGINT ignored,
    # and then interrupt_main does nothing.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.25, _thread.interrupt_main)
    try:
        start = time.perf_counter()
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            strata_rt.render(SEED, **settings)
        stopped = time.perf_counter() - start
    finally:
        timer.cancel()
        timer.join()
        signal.signal(signal.SIGINT, previous)
    # Where no pass's end checked, the interrupt would come only after
    # the whole render, when Python next looks for signals.
    assert stopped < 10.0, f"stopped after {stopped:.2f} s"

"""render's noise target: pixels stop at their own counts, which the spp
AOV gives, and the array stays linear whatever the exposure and curve."""

import numpy as np

import helpers
import strata_rt

SCENE = helpers.REPO / "scenes" / "soft-shadow.toml"


def test_a_noise_target_gives_each_pixel_its_count():
    image, aovs = strata_rt.render(SCENE, width=32, height=24, noise=0.05, spp=256, aovs=["spp"])
    spp = aovs["spp"]
    assert spp.shape == (24, 32)
    assert spp.min() >= 4 and spp.max() <= 256  # the first decision is after 4 samples
    assert spp.min() < spp.max(), "every pixel took the same count"
    again = strata_rt.render(SCENE, width=32, height=24, noise=0.05, spp=256, threads=1)
    np.testing.assert_array_equal(image.view(np.uint32), again.view(np.uint32))


def test_tone_curve_leaves_the_array_linear():
    a = strata_rt.render(SCENE, width=16, height=12, spp=2)
    b = strata_rt.render(SCENE, width=16, height=12, spp=2, exposure=2.0, tonemap="filmic")
    np.testing.assert_array_equal(a.view(np.uint32), b.view(np.uint32))

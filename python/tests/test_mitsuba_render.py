"""Renders through the plugin: two brdf-lab samplers of the same BRDF give the same image
within noise (both estimators are unbiased), in scalar_rgb and in llvm_ad_rgb."""

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed (pip install './python[mitsuba]')")
dr = pytest.importorskip("drjit")


def scene(sampler):
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {
            "type": "perspective", "fov": 30,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": 8, "height": 8, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": 64},
        },
        "emitter": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        "light": {"type": "point", "position": [2, 2, 3], "intensity": {"type": "rgb", "value": 20.0}},
        "ball": {"type": "sphere", "bsdf": {"type": "brdf_lab", "brdf": "phong:n=10", "sampler": sampler, "options": "slices=16"}},
    }


def render_pair(variant):
    mi.set_variant(variant)
    import brdf_lab.mitsuba as plugin

    plugin.register()
    if not variant.startswith("scalar"):
        plugin.evaluated_mode()
    imgs = [np.array(mi.render(mi.load_dict(scene(s)), seed=s_i)) for s_i, s in enumerate(["adaptive", "cosine"])]
    return imgs


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_two_samplers_render_the_same_image(variant):
    if variant not in mi.variants():
        pytest.skip(f"{variant} not available")
    try:
        a, b = render_pair(variant)
    except Exception as e:  # noqa: BLE001
        if variant.startswith("llvm") and "LLVM" in str(e):
            pytest.skip(f"no LLVM: {e}")
        raise
    assert a.shape == b.shape == (8, 8, 3)
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(b))
    # the sphere covers the image centre; compare the mean radiance of the whole frame
    # (measured in llvm_ad_rgb: 0.9603 / 0.9501, 1.1 % apart; a plugin whose sample weight is
    # ×1.15 renders 9 % brighter and fails this bound — checked by hand)
    ma, mb = a.mean(), b.mean()
    assert ma > 0
    assert abs(ma - mb) < 0.05 * ma, (ma, mb)

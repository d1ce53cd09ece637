"""flarebench.render: frames equal to `flarebench render`'s EXR bit for bit, their layers,
lights in every form, the GIL released while drawing, and errors as exceptions.

Frames are tiny (64×36 and 48×32) at the fast preset, so the suite takes seconds.
"""

import sys
import threading

import numpy as np
import pytest

import flarebench
from exr import read_exr

SIZE = (64, 36)
# Ghosts plus starbursts against the composed image: the starburst is added to the ghosts in
# more than one step, so the sums differ in the last bits (measured: at most 7.3e-7 relative
# on 0.5% of the pixels of the Heliar's 64×36 frame).
LAYER_SUM_RTOL = 1e-6


def bits(a):
    """The float32 pixels' bit patterns: equal arrays of these are equal bit for bit."""
    assert a.dtype == np.float32
    return a.view(np.uint32)


def cli_render(cli, tmp_path, lens, *args):
    """`flarebench render LENS ARGS… --backend cpu -o x.exr`, read back."""
    out = tmp_path / "x.exr"
    cli("render", lens, *args, "--backend", "cpu", "-o", out)
    return read_exr(out)


def test_a_frame_is_h_by_w_by_3_float32_finite_and_lit():
    img = flarebench.render("heliar-tronnier", [(8, 60)], size=SIZE, quality="fast")
    assert img.shape == (36, 64, 3)
    assert img.dtype == np.float32
    assert img.flags.c_contiguous
    assert np.isfinite(img).all()
    assert (img >= 0).all()
    assert img.sum() > 0


# (CLI arguments after the lens, render keyword arguments): the same frame both ways.
CASES = {
    "one light": (
        ["--light", "8,60", "--size", "64x36", "--quality", "fast"],
        dict(lights=[(8, 60)], size=(64, 36), quality="fast"),
    ),
    "two coloured lights and an iris, ghosts only": (
        [
            "--light", "5,30,2,3200",
            "--light", "12.5,200,0.5,1:0.8:0.6",
            "--size", "48x32",
            "--quality", "fast",
            "--iris-blades", "6",
            "--iris-rotation-deg", "15",
            "--iris-roundness", "0.25",
            "--starburst", "off",
        ],
        dict(
            lights=[(5, 30, 2, 3200), {"theta": 12.5, "phi": 200, "intensity": 0.5, "colour": (1, 0.8, 0.6)}],
            size=(48, 32),
            quality="fast",
            aperture={"blades": 6, "rotation_deg": 15, "roundness": 0.25},
            starburst=False,
        ),
    ),
    "a light placed by its pixel, starbursts only, four reflections": (
        [
            "--light-at", "40,10",
            "--size", "64x36",
            "--quality", "fast",
            "--starburst", "only",
            "--reflections", "4",
            "--starburst-texels", "128",
        ],
        dict(
            lights=[{"x": 40, "y": 10}],
            size=(64, 36),
            quality="fast",
            starburst="only",
            reflections=4,
            starburst_texels=128,
        ),
    ),
    "the default preset, no coarse drawing": (
        ["--light", "10,300", "--size", "48x32", "--max-downscale", "1"],
        dict(lights="10,300", size=(48, 32), max_downscale=1),
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_the_frame_equals_the_cli_exr_bit_for_bit(case, cli, tmp_path):
    args, kwargs = CASES[case]
    expected = cli_render(cli, tmp_path, "heliar-tronnier", *args)
    got = flarebench.render("heliar-tronnier", **kwargs)
    assert got.shape == expected.shape
    assert got.sum() > 0
    np.testing.assert_array_equal(bits(got), bits(expected))


def test_layers_are_the_cli_frames_with_starbursts_off_and_only(cli, tmp_path):
    lens = flarebench.Lens("heliar-tronnier")
    layers = flarebench.render(lens, (8, 60), size=SIZE, quality="fast", layers=True)
    assert sorted(layers) == ["ghosts", "image", "starbursts"]
    base = ["--light", "8,60", "--size", "64x36", "--quality", "fast"]
    for key, mode in [("image", "on"), ("ghosts", "off"), ("starbursts", "only")]:
        expected = cli_render(cli, tmp_path, "heliar-tronnier", *base, "--starburst", mode)
        np.testing.assert_array_equal(bits(layers[key]), bits(expected), err_msg=key)
    assert layers["ghosts"].sum() > 0 and layers["starbursts"].sum() > 0
    np.testing.assert_allclose(
        layers["ghosts"] + layers["starbursts"], layers["image"], rtol=LAYER_SUM_RTOL, atol=0
    )


def test_layers_hold_only_what_the_frame_is_made_of():
    only = flarebench.render("heliar-tronnier", (8, 60), size=SIZE, quality="fast", starburst="only", layers=True)
    assert sorted(only) == ["image", "starbursts"]
    off = flarebench.render("heliar-tronnier", (8, 60), size=SIZE, quality="fast", starburst=False, layers=True)
    assert sorted(off) == ["ghosts", "image"]
    np.testing.assert_array_equal(off["ghosts"], off["image"])


def test_lights_as_strings_tuples_dicts_and_alone_give_the_same_frame():
    kw = dict(size=SIZE, quality="fast", starburst=False)
    ref = flarebench.render("heliar-tronnier", ["8,60,2,3200"], **kw)
    for lights in [
        "8,60,2,3200",
        (8, 60, 2, 3200),
        [(8.0, 60.0, 2.0, 3200.0)],
        [[8, 60, 2, "3200"]],
        {"theta": 8, "phi": 60, "intensity": 2, "color": 3200},
    ]:
        np.testing.assert_array_equal(bits(flarebench.render("heliar-tronnier", lights, **kw)), bits(ref))


def test_a_thread_runs_python_while_another_renders():
    # With a switch interval far longer than the render, a thread that keeps the GIL is never
    # asked to give it up: the main thread could run again only after the render returned.
    # It runs during it only because the render releases the GIL.
    started, done = threading.Event(), threading.Event()
    result = {}

    def work():
        started.set()
        result["img"] = flarebench.render("heliar-tronnier", (8, 60), size=(160, 90), quality="fast")
        done.set()

    old = sys.getswitchinterval()
    sys.setswitchinterval(100.0)
    try:
        worker = threading.Thread(target=work)
        worker.start()
        started.wait()
        ran_during_render = 0
        while not done.is_set():
            ran_during_render += 1
            done.wait(0.001)
        worker.join()
    finally:
        sys.setswitchinterval(old)
    assert ran_during_render > 0
    assert result["img"].sum() > 0


def test_two_threads_render_at_once_and_get_the_serial_frames():
    args = [((8, 60), "heliar-tronnier"), ((12, 250), "double-gauss-50mm")]
    serial = [flarebench.render(lens, light, size=SIZE, quality="fast") for light, lens in args]
    out = [None, None]

    def work(i):
        light, lens = args[i]
        out[i] = flarebench.render(lens, light, size=SIZE, quality="fast")

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for got, expected in zip(out, serial):
        np.testing.assert_array_equal(bits(got), bits(expected))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(lights=[(95, 0)]), "THETA must be in"),
        (dict(lights=[(8, 60, -1)]), "INTENSITY"),
        (dict(lights=[]), "at least one light"),
        (dict(lights=[{"theta": 8}]), "needs either"),
        (dict(lights=[(8, "east")]), "phi `east` is not a number"),
        (dict(lights=[(8, 60)], size=(0, 10)), "between 1 and 16384"),
        (dict(lights=[(8, 60)], quality="best"), "quality"),
        (dict(lights=[(8, 60)], reflections=3), "reflections"),
        (dict(lights=[(8, 60)], max_downscale=3), "power of two"),
        (dict(lights=[(8, 60)], aperture={"blades": 6, "roundness": 2}), "iris"),
        (dict(lights=[(8, 60)], aperture={"petals": 6}), "aperture key `petals`"),
        (dict(lights=[(8, 60)], starburst="maybe"), "starburst `maybe`"),
        (dict(lights=[(8, 60)], starburst_texels=0), "starburst-texels"),
        (dict(lights=[(8, 60)], backend="tpu"), "backend `tpu`"),
    ],
)
def test_bad_arguments_raise_value_error(kwargs, message):
    kwargs = dict(size=SIZE, quality="fast") | kwargs
    with pytest.raises(ValueError, match=message):
        flarebench.render("heliar-tronnier", **kwargs)


def test_a_missing_aperture_mask_raises_value_error_naming_it(tmp_path):
    missing = tmp_path / "iris.png"
    with pytest.raises(ValueError, match="iris.png"):
        flarebench.render("heliar-tronnier", (8, 60), size=SIZE, quality="fast", aperture=missing)


def test_an_unknown_lens_name_raises_file_not_found():
    with pytest.raises(FileNotFoundError):
        flarebench.render("no-such-lens-xyz", (8, 60), size=SIZE)

"""flarebench.Sampler: samples equal to `flarebench dataset`'s files bit for bit (layers and
annotation), a pure function of (seed, index), the GIL released, pickling, and the sampler
file's errors as exceptions naming the line and field.

The sampler draws 64×48 frames at the fast preset from two small lenses, so the suite
takes seconds.
"""

import json
import pickle
import sys
import threading

import numpy as np
import pytest

import flarebench
from exr import read_channels, read_layer

# Sample 0: double-gauss-50mm, a circular stop, one light; sample 1: heliar-tronnier, an
# iris, two lights. Both have starbursts on the frame.
SEED = 2
# Per-light layers on, so every kind of layer is compared; no PNG (not a layer).
CONFIG = """\
size = [64, 48]
quality = "fast"
starburst_texels = 64

[lenses]
names = ["heliar-tronnier", "double-gauss-50mm"]

[lights]
count = [1, 2]
ev = [0, 2]

[layers]
per_light = true
png = false
"""


def bits(a):
    """The float32 pixels' bit patterns: equal arrays of these are equal bit for bit."""
    assert a.dtype == np.float32
    return a.view(np.uint32)


@pytest.fixture(scope="module")
def config_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("sampler") / "sampler.toml"
    path.write_text(CONFIG)
    return path


@pytest.fixture(scope="module")
def cli_dataset(cli, config_file):
    """`flarebench dataset --count 2 --seed SEED --config sampler.toml -o DIR`: DIR."""
    out = config_file.parent / "flares"
    cli("dataset", "--count", 2, "--seed", SEED, "--config", config_file, "-o", out)
    return out


@pytest.fixture(scope="module")
def sampler():
    return flarebench.Sampler(CONFIG)


@pytest.mark.parametrize("index", [0, 1])
def test_a_rendered_sample_equals_the_cli_files_bit_for_bit(sampler, cli_dataset, index):
    got = sampler.render(SEED, index)
    stem = f"{index:08d}"
    channels = read_channels(cli_dataset / "samples" / f"{stem}.exr")
    annotation = json.loads((cli_dataset / "samples" / f"{stem}.json").read_text())

    assert got["annotation"] == annotation
    assert sorted(channels) == annotation["channels"]
    n_lights = len(annotation["sample"]["lights"])
    assert len(got["lights"]) == n_lights
    layers = {"": got["image"], "ghosts": got["ghosts"], "starburst": got["starburst"]}
    layers.update({f"light{k}": img for k, img in enumerate(got["lights"])})
    assert 3 * len(layers) + 1 == len(channels)
    for name, img in layers.items():
        assert img.shape == (48, 64, 3) and img.dtype == np.float32, name
        np.testing.assert_array_equal(bits(img), bits(read_layer(channels, name)), err_msg=name)
    assert got["ghost_id"].shape == (48, 64) and got["ghost_id"].dtype == np.uint32
    np.testing.assert_array_equal(got["ghost_id"], channels["ghost_id"])
    assert got["ghosts"].sum() > 0 and got["starburst"].sum() > 0
    ids = {g["id"] for g in annotation["ghosts"]}
    assert set(np.unique(got["ghost_id"])) - {0} <= ids


def test_the_sampled_parameters_are_the_annotations_and_the_config_the_datasets(
    sampler, cli_dataset
):
    info = json.loads((cli_dataset / "dataset.json").read_text())
    assert sampler.config == info["sampler"]
    assert [list(l) for l in sampler.lenses] == info["lenses"]
    assert sampler.size == (64, 48)
    for index in (0, 1):
        annotation = json.loads((cli_dataset / "samples" / f"{index:08d}.json").read_text())
        assert sampler.sample(SEED, index) == annotation["sample"]


def test_a_sample_depends_on_the_seed_and_index_alone(config_file):
    a, b = flarebench.Sampler(CONFIG), flarebench.Sampler(config_file)
    first = a.render(SEED, 1)
    b.render(SEED + 1, 0)  # another sample drawn first: no state carries over
    again = b.render(SEED, 1)
    assert first["annotation"] == again["annotation"]
    for key in ("image", "ghosts", "starburst"):
        np.testing.assert_array_equal(bits(first[key]), bits(again[key]))
    np.testing.assert_array_equal(first["ghost_id"], again["ghost_id"])
    assert a.sample(SEED, 0) != a.sample(SEED, 1)
    assert a.sample(SEED, 0) != a.sample(SEED + 1, 0)


def test_layers_follow_the_sampler_and_defaults_need_no_config():
    s = flarebench.Sampler(
        CONFIG.replace("per_light = true", "ghost_id = false\nstarburst = false")
    )
    got = s.render(SEED, 0)
    assert set(got) == {"image", "ghosts", "annotation"}
    np.testing.assert_array_equal(bits(got["image"]), bits(got["ghosts"]))
    assert got["annotation"]["channels"] == ["B", "G", "R", "ghosts.B", "ghosts.G", "ghosts.R"]
    defaults = flarebench.Sampler()
    assert defaults.size == (512, 512) and len(defaults.lenses) == 19
    assert defaults.toml == "" and flarebench.Sampler("").config == defaults.config


def test_a_sampler_pickles_and_draws_the_same_samples(sampler):
    again = pickle.loads(pickle.dumps(sampler))
    assert again.toml == CONFIG
    assert again.sample(SEED, 3) == sampler.sample(SEED, 3)


def test_a_thread_runs_python_while_another_renders_a_sample(sampler):
    # As test_render's: with a switch interval far longer than the render, the main thread
    # runs during it only because the render releases the GIL.
    started, done = threading.Event(), threading.Event()
    result = {}

    def work():
        started.set()
        result["out"] = sampler.render(SEED, 0)
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
    assert result["out"]["image"].sum() > 0


def test_a_bad_field_raises_value_error_with_the_line_and_field(tmp_path):
    with pytest.raises(
        ValueError,
        match=r"sampler `<string>`, line 2, column 6, field `lights\.ev`: the range \[4, 1\]",
    ):
        flarebench.Sampler("[lights]\nev = [4, 1]\n")
    path = tmp_path / "bad.toml"
    path.write_text('size = [64, 48]\n[lenses]\nnmes = ["heliar-tronnier"]\n')
    with pytest.raises(
        ValueError, match=r"bad\.toml`, line 3, column 1, field `lenses\.nmes`: unknown field"
    ):
        flarebench.Sampler(path)
    with pytest.raises(ValueError, match=r"field `lenses\.names`"):
        flarebench.Sampler('[lenses]\nnames = ["no-such-lens-anywhere"]\n')
    with pytest.raises(FileNotFoundError, match="could not read the sampler `missing.toml`"):
        flarebench.Sampler("missing.toml")
    with pytest.raises(ValueError, match="is not None, a path or a sampler's TOML text"):
        flarebench.Sampler(3)

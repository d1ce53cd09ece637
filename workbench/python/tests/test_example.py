"""examples/torch_loader.py: sample i is the sampler's (seed, i), batches stack."""

import importlib.util
from pathlib import Path

import numpy as np

import flarebench

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "torch_loader.py"


def load_example():
    spec = importlib.util.spec_from_file_location("torch_loader", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_sample_is_the_samplers_sample_of_the_seed_and_index():
    ex = load_example()
    a = ex.FlareDataset(4, seed=7, size=32)
    b = ex.FlareDataset(4, seed=7, size=32)
    first, info = a[2]
    # Drawn in another order by another dataset: the same bits.
    b[0]
    again, info_again = b[2]
    assert info == info_again
    assert info["index"] == 2 and info["lens"] in ex.LENSES
    first, again = np.asarray(first), np.asarray(again)
    assert first.shape == (3, 32, 32) and first.dtype == np.float32
    assert first.sum() > 0
    np.testing.assert_array_equal(first.view(np.uint32), again.view(np.uint32))
    # The sampler's own render of (7, 2), as `flarebench dataset --seed 7` draws sample 2.
    direct = flarebench.Sampler(ex.sampler_toml(32)).render(7, 2)["image"]
    np.testing.assert_array_equal(first.view(np.uint32), direct.transpose(2, 0, 1).view(np.uint32))
    assert a.params(3) != a.params(2)
    assert ex.FlareDataset(4, seed=8).params(2) != a.params(2)


def test_numpy_batches_stack_every_sample():
    ex = load_example()
    batches = list(ex.numpy_batches(ex.FlareDataset(5, size=16), batch_size=2))
    assert [b[0].shape for b in batches] == [(2, 3, 16, 16), (2, 3, 16, 16), (1, 3, 16, 16)]
    assert [[i["index"] for i in b[1]] for b in batches] == [[0, 1], [2, 3], [4]]

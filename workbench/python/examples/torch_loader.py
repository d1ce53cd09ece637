"""Flares for training, generated on the fly: a PyTorch-style dataset over flarebench.Sampler.

Sample ``i`` is sample ``i`` of ``flarebench dataset --seed SEED --config sampler.toml``:
``flarebench.Sampler`` draws its lens, f-number, aperture and lights from (seed, i) alone and
renders it, so every worker, epoch and machine gets the same bits, equal to the CLI's files.
The dataset has ``__len__`` and ``__getitem__``; with PyTorch installed it is a
``torch.utils.data.Dataset`` fed to a ``DataLoader`` (workers render in parallel, the GIL
released while they do; the sampler pickles to reach them), and without it the same samples
are batched with NumPy.

    python workbench/python/examples/torch_loader.py            # 8 samples, 64×64
    python workbench/python/examples/torch_loader.py --count 32 --size 256
    python workbench/python/examples/torch_loader.py --config sampler.toml
"""

import argparse

import numpy as np

import flarebench

try:
    import torch
    from torch.utils.data import DataLoader, Dataset
except ImportError:  # the example runs without torch: NumPy batches instead
    torch = None
    Dataset = object

# Lenses to draw from (bundled names; any lens file path works too).
LENSES = ["heliar-tronnier", "double-gauss-50mm", "cooke-triplet-25mm"]


def sampler_toml(size, lenses=LENSES):
    """A small sampler (docs/datasets.md § The sampler): square frames at the fast preset."""
    names = ", ".join(f'"{n}"' for n in lenses)
    return f"""\
size = [{size}, {size}]
quality = "fast"
starburst_texels = 64

[lenses]
names = [{names}]

[lights]
count = [1, 2]
ev = [-2, 4]
"""


class FlareDataset(Dataset):
    """``count`` flares, sample ``i`` the sampler's sample (seed, i).

    ``config`` is a sampler file, its TOML text, or None for ``sampler_toml(size)``. A
    sample is ``(image, info)``: the flare as a 3×H×W float32 array (a tensor with torch),
    linear RGB, and a few of its parameters (``index``, ``lens``, ``f_number``, ``lights``;
    numbers and strings, which a DataLoader collates). ``render(i)`` gives every layer and the
    whole annotation.
    """

    def __init__(self, count, seed=0, size=64, config=None):
        self.count = count
        self.seed = seed
        self.sampler = flarebench.Sampler(sampler_toml(size) if config is None else config)

    def __len__(self):
        return self.count

    def params(self, index):
        """The sample's parameters, drawn without rendering: a function of (seed, index)."""
        return self.sampler.sample(self.seed, index)

    def render(self, index):
        """The sample rendered: ``image``, ``ghosts``, ``starburst``, ``ghost_id``, …, and its
        ``annotation`` (docs/python.md § Datasets)."""
        if not 0 <= index < self.count:
            raise IndexError(index)
        return self.sampler.render(self.seed, index)

    def __getitem__(self, index):
        out = self.render(index)
        sample = out["annotation"]["sample"]
        info = {
            "index": index,
            "lens": sample["lens"],
            "f_number": out["annotation"]["lens"]["working_f_number"],
            "lights": len(sample["lights"]),
        }
        chw = np.ascontiguousarray(out["image"].transpose(2, 0, 1))
        return (torch.from_numpy(chw) if torch is not None else chw), info


def numpy_batches(dataset, batch_size):
    """Batches as a DataLoader without shuffling gives them, for when torch is absent."""
    for start in range(0, len(dataset), batch_size):
        samples = [dataset[i] for i in range(start, min(start + batch_size, len(dataset)))]
        yield np.stack([s[0] for s in samples]), [s[1] for s in samples]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--count", type=int, default=8)
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--batch-size", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--config", help="a sampler file (default: a small one, --size square)")
    args = ap.parse_args()
    dataset = FlareDataset(args.count, seed=args.seed, size=args.size, config=args.config)
    if torch is not None:
        # The default collate stacks the images and each parameter (a tensor or a list).
        batches = DataLoader(dataset, batch_size=args.batch_size, num_workers=2)
    else:
        batches = numpy_batches(dataset, args.batch_size)
    for images, params in batches:
        lenses = params["lens"] if isinstance(params, dict) else [p["lens"] for p in params]
        print(f"batch {tuple(images.shape)} {images.dtype}: {', '.join(lenses)}")


if __name__ == "__main__":
    main()

"""Flares for training, generated on the fly: a PyTorch-style dataset over flarebench.

Each sample is a pure function of (seed, index): the lens, the light (angle, azimuth,
intensity in stops, colour temperature) and the iris are drawn from a NumPy generator seeded
with both, then rendered by ``flarebench.render``. The dataset has ``__len__`` and
``__getitem__``; with PyTorch installed it is a ``torch.utils.data.Dataset`` fed to a
``DataLoader`` (workers render in parallel, and the GIL is released while they do), and
without it the same samples are batched with NumPy.

    python workbench/python/examples/torch_loader.py            # 8 samples, 64×64
    python workbench/python/examples/torch_loader.py --count 32 --size 256
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


class FlareDataset(Dataset):
    """``count`` flares of ``size``×``size`` pixels, sample ``i`` drawn from (seed, i).

    A sample is ``(image, params)``: the flare as a 3×H×W float32 array (a tensor with
    torch), linear RGB, and the parameters it was drawn with.
    """

    def __init__(self, count, seed=0, size=64, lenses=LENSES, quality="fast"):
        self.count = count
        self.seed = seed
        self.size = size
        self.lenses = list(lenses)
        self.quality = quality
        self._loaded = {}  # name -> flarebench.Lens, read once per process

    def __len__(self):
        return self.count

    def params(self, index):
        """The sample's parameters: a function of (seed, index) alone."""
        rng = np.random.default_rng([self.seed, index])
        return {
            "lens": self.lenses[rng.integers(len(self.lenses))],
            "theta": float(rng.uniform(0.5, 20.0)),
            "phi": float(rng.uniform(0.0, 360.0)),
            "intensity": float(2.0 ** rng.uniform(-2.0, 4.0)),
            "kelvin": float(rng.uniform(2700.0, 7500.0)),
            "blades": int(rng.choice([0, 5, 6, 7, 9])),
            "roundness": float(rng.uniform(0.0, 0.5)),
        }

    def _lens(self, name):
        if name not in self._loaded:
            self._loaded[name] = flarebench.Lens(name)
        return self._loaded[name]

    def __getitem__(self, index):
        if not 0 <= index < self.count:
            raise IndexError(index)
        p = self.params(index)
        aperture = {"blades": p["blades"], "roundness": p["roundness"]} if p["blades"] else None
        image = flarebench.render(
            self._lens(p["lens"]),
            [(p["theta"], p["phi"], p["intensity"], p["kelvin"])],
            size=(self.size, self.size),
            quality=self.quality,
            aperture=aperture,
        )
        chw = np.ascontiguousarray(image.transpose(2, 0, 1))
        return (torch.from_numpy(chw) if torch is not None else chw), p


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
    args = ap.parse_args()
    dataset = FlareDataset(args.count, seed=args.seed, size=args.size)
    if torch is not None:
        # The default collate stacks the images and turns each parameter into a list.
        batches = DataLoader(dataset, batch_size=args.batch_size, num_workers=2)
    else:
        batches = numpy_batches(dataset, args.batch_size)
    for images, params in batches:
        lenses = params["lens"] if isinstance(params, dict) else [p["lens"] for p in params]
        print(f"batch {tuple(images.shape)} {images.dtype}: {', '.join(lenses)}")


if __name__ == "__main__":
    main()

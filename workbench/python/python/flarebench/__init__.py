"""flarebench: physically based lens flare from real lens designs.

``Lens`` reads a lens file or a bundled lens by name and gives its paraxial data;
``render`` draws a flare frame as ``flarebench render`` does and returns it as an
H×W×3 float32 NumPy array of linear RGB (or its layers); ``Sampler`` draws the samples of
``flarebench dataset`` from (seed, index) and renders them with their layers and
annotation. The guide is docs/python.md in the flarebench repository.
"""

from ._flarebench import Lens, Sampler, __version__, render

__all__ = ["Lens", "Sampler", "render", "__version__"]

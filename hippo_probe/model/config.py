"""Defaults of the network (one place for its numbers)."""

from __future__ import annotations

from dataclasses import dataclass

from .._validators import check_number, check_option
from ..world.config import FEATURES, WorldConfig

#: Matmul precisions of the LSTM's training path (see :class:`PeepholeLSTM`).
PRECISIONS = ("fp32", "bf16")

#: The named model variants (:mod:`hippo_probe.model.variants`); "faithful" is the
#: study's network.
VARIANTS = ("faithful", "nonneg", "dale", "placecells")


def native_bf16() -> bool:
    """Whether this CPU computes bf16 matmuls in hardware (AVX512-BF16 or AMX).

    Without them oneDNN emulates bf16 and the bf16 training step is far slower than
    float32 (measured on an AMD EPYC without AVX-512: 37.7 s vs 1.84 s per step of batch
    64 x 500 steps x 256 units, one thread).
    """
    import torch

    return bool(torch.cpu._is_avx512_bf16_supported() or torch.cpu._is_amx_tile_supported())


def resolve_precision(precision: str) -> str:
    """``"auto"`` -> ``"bf16"`` where :func:`native_bf16`, else ``"fp32"``; others as given."""
    check_option("precision", precision, ("auto", *PRECISIONS))
    if precision == "auto":
        return "bf16" if native_bf16() else "fp32"
    return precision


@dataclass(frozen=True)
class ModelConfig:
    """Architecture of a :class:`~hippo_probe.model.Navigator`.

    Attributes
    ----------
    hidden_size : int
        256 LSTM units, as in the study.
    n_classes : int
        Size of the softmax readout over arenas (100 for the specialized task, 0 = none).
    input_scale : tuple of float
        Each input feature is divided by its scale so that all inputs are O(1) (the raw
        displacement is ~0.06 m per step, the contact distance < 0.05 m). See
        :func:`input_scale_for`.
    forget_bias : float
        Initial forget-gate bias (1.0, Jozefowicz et al. 2015).
    precision : str
        Matmul precision of the LSTM's training path, "fp32" or "bf16" (bf16 matmuls on
        the CPU's AMX units, state and gradient accumulation in float32). Forward passes
        without autograd (evaluation, ``record``) always run float32, so a network loaded
        from a file behaves the same whichever precision trained it.
    variant : str
        "faithful" (the study's network, the default) or a labelled departure from it:
        "nonneg", "dale", "placecells" (:mod:`hippo_probe.model.variants`).
    n_place_cells : int
        Place cells of the "placecells" output: 256, as many as the units.
    place_cell_width : float
        Their tuning width (m): 0.05 m, about the generalized network's error after 100 s
        (0.08 m) and a sixth of the small arenas' radius, so a handful of cells are active
        at any position and the decoded centre can resolve the network's precision. Even
        noise-free targets decode 2.5 cm off on average (5.5 cm at the 95th percentile,
        positions uniform in the 1 m square): the centres' random density and the pull
        inwards near the disk's edge. Widths 0.03-0.1 m give 2.5-2.9 cm; this floor adds in
        quadrature to the network's own error (about 5% at 8 cm).
    place_cell_extent : float
        Centres uniform in a disk of this radius (m) around the target frame's origin:
        0.66 m, twice the small arenas' mean radius, the reach of a start-relative
        position (the generalized task's target).
    """

    hidden_size: int = 256
    n_classes: int = 0
    input_scale: tuple = (1.0,) * len(FEATURES)
    forget_bias: float = 1.0
    precision: str = "fp32"
    variant: str = "faithful"
    n_place_cells: int = 256
    place_cell_width: float = 0.05
    place_cell_extent: float = 0.66

    #: Largest architecture built, checked before any parameter is allocated: 16,384
    #: units (4 GiB of recurrent weights in float32) and 100,000 classes, far above any
    #: network of the study, far below what a crafted file could declare.
    MAX_HIDDEN = 16384
    MAX_CLASSES = 100_000

    def __post_init__(self):
        check_option("precision", self.precision, PRECISIONS)
        check_option("variant", self.variant, VARIANTS)
        check_number("n_place_cells", self.n_place_cells, low=2, low_inclusive=True,
                     high=self.MAX_CLASSES, high_inclusive=True, integer=True)
        for name in ("place_cell_width", "place_cell_extent"):
            check_number(name, getattr(self, name), low=0)
        check_number("hidden_size", self.hidden_size, low=1, low_inclusive=True,
                     high=self.MAX_HIDDEN, high_inclusive=True, integer=True)
        check_number("n_classes", self.n_classes, low=0, low_inclusive=True,
                     high=self.MAX_CLASSES, high_inclusive=True, integer=True)

    @property
    def input_size(self) -> int:
        return len(self.input_scale)


#: Typical size (rad) of the heading change over one network step, used to scale the
#: ``dhd`` input: with 1 rad/s turning (MotionConfig.turn_sd) a 0.4 s step turns ~0.4 rad.
TURN_SCALE = 0.5


def input_scale_for(world: WorldConfig) -> tuple:
    """Per-feature input scales from the world: the mean displacement per step for dx, dy;
    the touch range for the contact distance; 1 for unit-range features (cos, sin, flag)
    and the turn per step's typical size (0.5 rad) for the heading change."""
    step = world.motion.mean_speed * world.motion.network_dt
    scale = {"dx": step, "dy": step, "dhd": TURN_SCALE,
             "contact_distance": world.sensors.touch_range}
    return tuple(float(scale.get(name, 1.0)) for name in FEATURES)

"""Defaults of a training run (one place for its numbers)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .._validators import check_number, check_option, check_positive
from ..model.config import PRECISIONS, VARIANTS
from ..tasks import TASKS
from ..world.config import WORLDS


@dataclass(frozen=True)
class TrainConfig:
    """Everything that defines a training run; saved in every checkpoint and log.

    Attributes
    ----------
    task : str
        "localization", "generalized" or "specialized".
    world : str
        "darkness" (the study's world, the default) or "compass": the world of every
        trial the run trains, validates and tests on. Saved with the network.
    n_trials : int or None
        Training-set size (trials 0 .. n-1 of the train split); None = the study's size
        (5,000 / 300,000 / 250,000).
    steps : int
        Budget in optimizer steps.
    batch_size : int
        64 sequences of 500 steps per step (global, across DDP ranks): large enough for
        stable gradients, small enough for ~1 step/s on 2 CPU cores.
    lr, lr_final : float
        Adam learning rate, cosine-decayed from ``lr`` (1e-3, Adam's default) to
        ``lr_final`` (1e-4) over the budget.
    clip_norm : float
        Gradient norm clip, 1.0 (LSTMs over 500 steps have rare exploding gradients).
    validate_every : int
        Steps between validations on the validation split.
    n_validation, n_test : int
        Validation and test trials (1,000 each: the whole splits).
    checkpoint_minutes : float
        Wall time between atomic checkpoints.
    threads : int
        torch (and numba) threads per process, pinned.
    seed : int
        Seed of the task splits (which trials exist).
    init_seed : int
        Seed of the parameter initialisation and of the order of training trials.
    hidden_size : int
        256 units, the study's size.
    class_weight : float or None
        Weight of the cross-entropy term; None = the rule of :func:`class_weight_rule`.
    init_from : str or None
        Checkpoint or pretrained name whose parameters initialise the network.
    train_only : str or None
        "classifier": freeze everything else and train the arena readout alone on
        cross-entropy (readout retraining, the study's Fig. 3F; task must be
        "specialized").
    device : str
        "cpu" (default) or "cuda".
    precision : str
        Matmul precision of training, "auto" (default), "fp32" or "bf16": bf16 runs the
        LSTM's matmuls on the CPU's AMX units (2-6x the float32 speed on a CPU that has
        them) with cell state, gate math, losses, gradient accumulation and Adam's
        parameters in float32. "auto" takes bf16 where the CPU computes it in hardware
        (AVX512-BF16 or AMX) and fp32 elsewhere, where bf16 is emulated and ~20x slower
        (:func:`hippo_probe.model.config.native_bf16`). Validation, test and the saved
        parameters are float32 either way. The two differ only in rounding, so a run may
        be resumed in the other precision (on another machine); the log lists the
        precision of every stretch of steps (``precision_from_step``). On bf16 hardware,
        bf16 is the better default: the same 1,000-step generalized run
        (darkness world) ended at validation error 0.159 m in bf16 and 0.151 m in fp32
        (5.4% apart; test 0.157 vs 0.152 m, 3.6%), while fp32 with another init seed
        ended at 0.157 m (3.9% from fp32, 1.4% from bf16): the gap is that between seeds,
        at 1.8x the speed (515 vs 924 s; ``analyses/precision_convergence.py``).
    stop_improvement : float or None
        Stop before the budget once the validation loss improved by less than this
        fraction over the last fifth of the steps done (0.01, the training issue's rule):
        ``1 - min(loss over all validations) / min(loss up to 0.8 step) < 0.01``. Checked
        at each validation from a quarter of the budget (at least 2,000 steps) on: the
        tasks have long early plateaus (a specialized network sat at chance accuracy
        for 8,000 steps, then fell to a fifth of that loss). None = run the whole budget.
    max_hours : float or None
        Stop before the budget once the run's wall time (summed over resumes) passes this
        many hours. None (default): the step budget is the cap. The training issue's cap
        is "about 10 hours of one core per run at the bf16 speed"; at that speed (0.73 s
        a step here with two runs side by side) 40,000 steps are 8.1 h, while a wall-time
        cap would also count the hours a run spent on slower hardware (float32, or bf16
        emulated) and end it steps short.
    variant : str
        "faithful" (the study's network, the default) or a labelled departure:
        "nonneg", "dale", "placecells" (:mod:`hippo_probe.model.variants`).
    activity_l1 : float
        Weight of an L1 cost on the units' activity, ``activity_l1 * mean |h|``, added to
        the loss (0: none, the study's loss). Used with the "nonneg" and "dale" variants.
    snapshot_every : int or None
        Save the current parameters every this many steps as
        ``snapshots/step_NNNNNN.pt`` in the run folder (loadable by
        :func:`hippo_probe.load_pretrained`), so that what the network holds can be
        measured along training afterwards (e.g. the arena probe against step). None
        (default): no snapshots.
    """

    task: str = "generalized"
    world: str = "darkness"
    n_trials: int | None = None
    steps: int = 5000
    batch_size: int = 64
    lr: float = 1e-3
    lr_final: float = 1e-4
    clip_norm: float = 1.0
    validate_every: int = 250
    n_validation: int = 1000
    n_test: int = 1000
    checkpoint_minutes: float = 3.0
    threads: int = 1
    seed: int = 0
    init_seed: int = 0
    hidden_size: int = 256
    class_weight: float | None = None
    init_from: str | None = None
    train_only: str | None = None
    device: str = "cpu"
    precision: str = "auto"
    stop_improvement: float | None = 0.01
    max_hours: float | None = None
    variant: str = "faithful"
    activity_l1: float = 0.0
    snapshot_every: int | None = None

    #: fields that do not change the parameters of the steps done (may differ on resume)
    RESUMABLE_CHANGES = ("threads", "checkpoint_minutes", "n_test", "precision",
                         "stop_improvement", "max_hours", "snapshot_every")

    def __post_init__(self):
        check_option("task", self.task, TASKS)
        check_option("world", self.world, WORLDS)
        if self.n_trials is not None:
            check_positive("n_trials", self.n_trials, integer=True)
        for name in ("steps", "batch_size", "validate_every", "n_validation", "n_test", "threads",
                     "hidden_size"):
            check_positive(name, getattr(self, name), integer=True)
        for name in ("lr", "lr_final", "clip_norm", "checkpoint_minutes"):
            check_positive(name, getattr(self, name))
        if self.class_weight is not None:
            check_number("class_weight", self.class_weight, low=0, low_inclusive=True)
        if self.train_only is not None:
            check_option("train_only", self.train_only, ("classifier",))
            if self.task != "specialized":
                raise ValueError(f"`train_only`='classifier' retrains the arena readout on "
                                 f"the specialized task; got task={self.task!r}")
            if self.init_from is None:
                raise ValueError("`train_only`='classifier' needs `init_from` (the network "
                                 "whose readout to retrain); got None")
            if self.class_weight is not None:
                raise ValueError(f"`class_weight` has no role when only the classifier is "
                                 f"trained (its loss is the cross-entropy); got "
                                 f"{self.class_weight}")
        check_option("device", self.device, ("cpu", "cuda"))
        check_option("precision", self.precision, ("auto", *PRECISIONS))
        if self.stop_improvement is not None:
            check_number("stop_improvement", self.stop_improvement, low=0, high=1)
        if self.max_hours is not None:
            check_positive("max_hours", self.max_hours)
        check_option("variant", self.variant, VARIANTS)
        check_number("activity_l1", self.activity_l1, low=0, low_inclusive=True)
        if self.snapshot_every is not None:
            check_positive("snapshot_every", self.snapshot_every, integer=True)

    def differences(self, other: "TrainConfig") -> dict:
        """Fields that differ and matter for the result: name -> (self, other)."""
        return {f.name: (getattr(self, f.name), getattr(other, f.name))
                for f in dataclasses.fields(self)
                if f.name not in self.RESUMABLE_CHANGES
                and getattr(self, f.name) != getattr(other, f.name)}

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "TrainConfig":
        names = {f.name for f in dataclasses.fields(cls)}
        # runs saved before `precision` and `world` existed were all float32 and all of the
        # compass world, whatever the defaults now
        d = {"precision": "fp32", "world": "compass", **d}
        return cls(**{k: v for k, v in d.items() if k in names})

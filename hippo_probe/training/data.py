"""Training trials in a reproducible order, read block by block from the trial cache.

The order of training trials is a pure function of ``(init_seed, step)``: epoch ``e``
visits the cache blocks in a random order (seeded by ``(init_seed, e)``) and the trials of
each block in a random order, and batch ``k`` is the ``k``-th slice of that sequence. So a
resumed run sees exactly the trials an uninterrupted one would, and consecutive batches
come from the same block (one decompression per ~15 batches, not one per trial).
"""

from __future__ import annotations

import numpy as np

from ..tasks import CACHE_CHUNK, cached_trials


class TrainingTrials:
    """Batches of the first ``n_trials`` train-split trials of a task, by step."""

    def __init__(self, task: str, n_trials: int, batch_size: int, *, world="darkness",
                 seed: int = 0, init_seed: int = 0, cache_dir=None):
        self.task, self.n_trials, self.batch_size = task, n_trials, batch_size
        self.world = world
        self.seed, self.init_seed, self.cache_dir = seed, init_seed, cache_dir
        self.batches_per_epoch = max(n_trials // batch_size, 1)
        self._order_epoch = None
        self._order = None
        self._blocks = {}

    def epoch_order(self, epoch: int) -> np.ndarray:
        if self._order_epoch != epoch:
            rng = np.random.default_rng([self.init_seed, epoch])
            n_blocks = -(-self.n_trials // CACHE_CHUNK)
            parts = []
            for block in rng.permutation(n_blocks):
                lo, hi = block * CACHE_CHUNK, min((block + 1) * CACHE_CHUNK, self.n_trials)
                parts.append(lo + rng.permutation(hi - lo))
            self._order, self._order_epoch = np.concatenate(parts), epoch
        return self._order

    def indices(self, step: int) -> np.ndarray:
        """Trial indices of the batch of optimizer step ``step``."""
        epoch, k = divmod(step, self.batches_per_epoch)
        order = self.epoch_order(epoch)
        take = np.arange(k * self.batch_size, (k + 1) * self.batch_size) % len(order)
        return order[take]

    def _block(self, block: int):
        if block not in self._blocks:
            if len(self._blocks) >= 2:                 # keep the current and next block
                self._blocks.pop(next(iter(self._blocks)))
            lo = block * CACHE_CHUNK
            n = min(CACHE_CHUNK, self.n_trials - lo)
            self._blocks[block] = cached_trials(self.task, n, "train", self.seed, first=lo,
                                                cache_dir=self.cache_dir, world=self.world)
        return self._blocks[block]

    def batch(self, indices: np.ndarray):
        """(inputs (T, b, F), target (T, b, 2), environment (b,)) of the given trials."""
        inputs, target, env = [], [], []
        for block in np.unique(indices // CACHE_CHUNK):
            sel = indices[indices // CACHE_CHUNK == block] - block * CACHE_CHUNK
            b = self._block(int(block))
            inputs.append(b.inputs[:, sel])
            target.append(b.target[:, sel])
            env.append(b.environment[sel])
        return (np.concatenate(inputs, axis=1), np.concatenate(target, axis=1),
                np.concatenate(env))

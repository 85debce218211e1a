"""The three tasks: reproducible trials, disjoint splits, fixed arenas, the trial cache."""

import hashlib
import shutil
from dataclasses import fields, replace

import numba
import numpy as np
import pytest
import zarr

from hippo_probe import tasks
from hippo_probe.tasks import (SPLITS, TASKS, TrialBatch, cached_trials, fixed_arenas,
                               make_trials, task_config)
from hippo_probe.world import FEATURES, NoiseModel, SensorConfig, contains, wall_distance

# sha1 of the fixed arenas' vertices in nanometres (rounded to 1e-9 m), computed once from
# the code that made them: any change of these arenas (code, seed, numpy's generator)
# would silently change the specialized task and invalidate trained networks.
PINNED_ARENAS = {
    "specialized": "db56caf289c4854cd766d04959faf1a39fa801fd",
    "localization": "981dd6ae9a75c2f92ca333fa81a5f6a6e4188a9c",
}


def assert_same_batch(a: TrialBatch, b: TrialBatch):
    for f in fields(TrialBatch):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype, f.name
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        else:
            assert x == y, f.name


def trial_digests(batch):
    """One digest per trial of everything sensed and everything true about it."""
    return [hashlib.sha1(batch.inputs[:, b].tobytes() + batch.position[:, b].tobytes())
            .hexdigest() for b in range(len(batch))]


@pytest.mark.parametrize("task", TASKS)
def test_the_same_seed_gives_identical_trials_however_batched(task):
    whole = make_trials(task, 10, "train", 3)
    joined = TrialBatch.concatenate([make_trials(task, 4, "train", 3, first=0),
                                     make_trials(task, 6, "train", 3, first=4)])
    assert_same_batch(whole, joined)
    assert_same_batch(whole.select(np.arange(4, 10)), make_trials(task, 6, "train", 3, first=4))
    assert_same_batch(whole.select(7), make_trials(task, 1, "train", 3, first=7))
    np.testing.assert_array_equal(whole.trial_index, np.arange(10))
    # ... and another seed gives other trials
    other = make_trials(task, 10, "train", 4)
    assert not set(trial_digests(whole)) & set(trial_digests(other))


def test_trials_do_not_depend_on_chunking_or_threads(monkeypatch):
    """make_trials works in chunks, on as many threads as numba may use: neither matters."""
    whole = {task: make_trials(task, 7, "test", 1) for task in TASKS}
    monkeypatch.setattr(tasks, "_CHUNK", 3)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        for task in TASKS:
            assert_same_batch(make_trials(task, 7, "test", 1), whole[task])
    finally:
        numba.set_num_threads(threads)


@pytest.mark.parametrize("task", TASKS)
def test_splits_never_share_a_trial(task):
    digests = [d for split in SPLITS for d in trial_digests(make_trials(task, 12, split, 0))]
    assert len(set(digests)) == len(digests) == 36


@pytest.mark.parametrize("task", TASKS)
def test_trial_batch_fields(task):
    n = 6
    batch = make_trials(task, n, "validation", 5)
    config = task_config(task)
    motion = config.world.motion
    t = motion.n_steps
    assert (batch.task, batch.split, batch.seed, batch.dt) == (task, "validation", 5, 0.4)
    assert len(batch) == n and batch.n_steps == t == 500
    expected = {"inputs": ((t, n, len(FEATURES)), np.float32), "target": ((t, n, 2), None),
                "position": ((t, n, 2), None), "start": ((n, 2), None),
                "head_direction": ((t, n), None), "contact": ((t, n), np.bool_),
                "environment": ((n,), None), "arena_vertices": ((n, 10, 2), None)}
    for name, (shape, dtype) in expected.items():
        value = getattr(batch, name)
        assert value.shape == shape, name
        if dtype is not None:
            assert value.dtype == dtype, name
    assert np.issubdtype(batch.environment.dtype, np.integer)
    assert np.isfinite(batch.inputs).all()
    hd = batch.head_direction
    assert ((hd >= -np.pi) & (hd < np.pi)).all()
    np.testing.assert_allclose(batch.time[[0, -1]], [0.4, 200.0])
    # every position of every trial is inside its arena
    assert contains(batch.arena_vertices, batch.position.transpose(1, 0, 2)).all()
    np.testing.assert_allclose(np.linalg.norm(batch.arena_vertices, axis=-1).mean(axis=1),
                               config.world.arena.mean_radius, rtol=1e-12)


def test_the_tasks_as_the_design_defines_them():
    clearance = SensorConfig().touch_range
    loc = make_trials("localization", 30, "train", 0)
    assert (loc.environment == 0).all()
    np.testing.assert_array_equal(loc.arena_vertices, np.broadcast_to(
        fixed_arenas("localization")[0], loc.arena_vertices.shape))
    np.testing.assert_array_equal(loc.target, loc.position)

    gen = make_trials("generalized", 30, "train", 0, first=100)
    np.testing.assert_array_equal(gen.environment, gen.trial_index)
    assert len({v.tobytes() for v in gen.arena_vertices}) == 30       # a new arena each
    np.testing.assert_allclose(gen.target, gen.position - gen.start[None], rtol=0,
                               atol=1e-15)

    spec = make_trials("specialized", 300, "train", 0)
    table = fixed_arenas("specialized")
    assert ((spec.environment >= 0) & (spec.environment < 100)).all()
    assert len(np.unique(spec.environment)) > 90                      # ~uniform over 100
    np.testing.assert_array_equal(spec.arena_vertices, table[spec.environment])
    assert (spec.start == 0).all()                                    # known start: centre
    np.testing.assert_array_equal(spec.target, spec.position)
    assert task_config("specialized").n_classes == 100

    for batch in (loc, gen):           # unknown start: uniform, not touching a wall
        inside = contains(batch.arena_vertices, batch.start[:, None])[:, 0]
        assert inside.all()
        distance, _, _ = wall_distance(batch.arena_vertices, batch.start[:, None])
        assert (distance >= clearance).all()
    # starts spread over the arena rather than piling up at its centre
    assert np.linalg.norm(loc.start, axis=1).max() > 0.5

    sizes = {task: task_config(task).split_size("train") for task in TASKS}
    assert sizes == {"localization": 5000, "generalized": 300_000, "specialized": 250_000}
    radii = {task: task_config(task).world.arena.mean_radius for task in TASKS}
    assert radii == {"localization": 1.0, "generalized": 0.33, "specialized": 0.33}


@pytest.mark.parametrize("task", ["specialized", "localization"])
def test_fixed_arenas_are_identical_on_every_machine(task):
    verts = fixed_arenas(task)
    assert verts.shape == (task_config(task).n_arenas, 10, 2)
    nanometres = np.rint(verts * 1e9).astype("<i8")
    assert hashlib.sha1(nanometres.tobytes()).hexdigest() == PINNED_ARENAS[task]
    assert len({v.tobytes() for v in verts}) == len(verts)
    # they do not depend on split or seed
    a = make_trials(task, 3, "test", 9).arena_vertices
    b = make_trials(task, 3, "train", 0).arena_vertices
    for v in (*a, *b):
        assert any(np.array_equal(v, w) for w in verts)


def test_empty_batches():
    for task in TASKS:
        batch = make_trials(task, 0, "train", 0)
        assert batch.inputs.shape == (500, 0, len(FEATURES))
        assert batch.start.shape == (0, 2) and batch.arena_vertices.shape == (0, 10, 2)


# --------------------------------------------------------------------------- cache
@pytest.fixture
def small_blocks(monkeypatch):
    """Cache blocks of 4 trials, so a test spans several blocks cheaply."""
    monkeypatch.setattr(tasks, "CACHE_CHUNK", 4)
    return 4


def block_paths(cache_dir):
    return sorted(p.name for p in cache_dir.glob("*/block*.zarr"))


@pytest.mark.parametrize("task", TASKS)
def test_cached_trials_are_the_made_trials(task, tmp_path, small_blocks, monkeypatch):
    made = make_trials(task, 10, "train", 2, first=3)
    cached = cached_trials(task, 10, "train", 2, first=3, cache_dir=tmp_path)
    assert_same_batch(cached, made)
    assert block_paths(tmp_path) == [f"block{k:06d}.zarr" for k in range(4)]   # trials 0-15

    # a second read comes from disk, not from the simulator
    def no_simulation(*args, **kwargs):
        raise AssertionError("trials regenerated instead of read from the cache")

    monkeypatch.setattr(tasks, "make_trials", no_simulation)
    assert_same_batch(cached_trials(task, 10, "train", 2, first=3, cache_dir=tmp_path), made)
    sub = cached_trials(task, 3, "train", 2, first=5, cache_dir=tmp_path)
    assert_same_batch(sub, made.select(np.arange(2, 5)))


def test_cache_never_serves_trials_of_another_world(tmp_path, small_blocks):
    cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path)
    compass = cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path, world="compass")
    assert_same_batch(compass, make_trials("generalized", 4, "train", 0, world="compass"))
    names = sorted(p.name for p in tmp_path.iterdir())
    assert len(names) == 2 and "compass" in names[0] and "darkness" in names[1]
    shutil.rmtree(tmp_path / names[0])
    config = task_config("generalized")
    quiet = replace(config, world=replace(config.world, noise=NoiseModel.noiseless()))
    got = cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path, config=quiet)
    assert_same_batch(got, make_trials("generalized", 4, "train", 0, config=quiet))
    assert len(list(tmp_path.iterdir())) == 2
    # nor of another split or seed
    other = cached_trials("generalized", 4, "test", 1, cache_dir=tmp_path)
    assert_same_batch(other, make_trials("generalized", 4, "test", 1))


@pytest.mark.parametrize("where", ["array", "rename"])
def test_an_interrupted_block_write_leaves_no_block_that_is_read(where, tmp_path, small_blocks,
                                                                 monkeypatch):
    calls = []
    original_create = zarr.Group.create_array

    def failing_create(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt("killed while writing")
        return original_create(self, *args, **kwargs)

    def failing_rename(src, dst):
        raise KeyboardInterrupt("killed before the rename")

    with monkeypatch.context() as patch:
        if where == "array":
            patch.setattr(zarr.Group, "create_array", failing_create)
        else:
            patch.setattr(tasks.os, "rename", failing_rename)
        with pytest.raises(KeyboardInterrupt):
            cached_trials("specialized", 6, "train", 0, cache_dir=tmp_path)
    assert block_paths(tmp_path) == []
    # the next run regenerates the block and gets the right trials
    got = cached_trials("specialized", 6, "train", 0, cache_dir=tmp_path)
    assert_same_batch(got, make_trials("specialized", 6, "train", 0))
    assert block_paths(tmp_path) == ["block000000.zarr", "block000001.zarr"]


def test_a_block_written_by_a_concurrent_process_is_kept(tmp_path, small_blocks, monkeypatch):
    """If another process renamed its identical block into place first, ours is dropped."""
    first = cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path)
    (store,) = tmp_path.iterdir()
    before = sorted(p.relative_to(store) for p in store.rglob("*"))
    original_exists = tasks.Path.exists
    asked = set()

    def not_yet_there(self):     # the block appears between our check and our rename
        if self.name.startswith("block") and self not in asked:
            asked.add(self)
            return False
        return original_exists(self)

    monkeypatch.setattr(tasks.Path, "exists", not_yet_there)
    again = cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path)
    assert_same_batch(again, first)
    assert asked                 # the race really happened
    monkeypatch.undo()
    assert sorted(p.relative_to(store) for p in store.rglob("*")) == before   # no leftovers


def test_an_interrupted_block_write_leaves_nothing_on_disk(tmp_path, small_blocks,
                                                           monkeypatch):
    def failing_rename(src, dst):
        raise KeyboardInterrupt("killed before the rename")

    monkeypatch.setattr(tasks.os, "rename", failing_rename)
    with pytest.raises(KeyboardInterrupt):
        cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path)
    assert [p for p in tmp_path.rglob("*") if p.is_file()] == []


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("call, name, value", [
    (lambda d: make_trials("navigation", 4), "task", "'navigation'"),
    (lambda d: make_trials("generalized", 4, "dev"), "split", "'dev'"),
    (lambda d: make_trials("generalized", -1), "n_trials", "-1"),
    (lambda d: make_trials("generalized", 4, first=-2), "first", "-2"),
    (lambda d: make_trials("generalized", 4, seed=-3), "seed", "-3"),
    (lambda d: task_config("navigation"), "task", "'navigation'"),
    (lambda d: task_config("generalized").split_size("dev"), "split", "'dev'"),
    (lambda d: cached_trials("navigation", 4, cache_dir=d), "task", "'navigation'"),
    (lambda d: cached_trials("generalized", 4, "dev", cache_dir=d), "split", "'dev'"),
    (lambda d: cached_trials("generalized", -1, cache_dir=d), "n_trials", "-1"),
    (lambda d: cached_trials("generalized", 4, first=-2, cache_dir=d), "first", "-2"),
    (lambda d: make_trials("generalized", 4, config=task_config("specialized")), "config",
     "'specialized'"),
])
def test_bad_input_raises_naming_parameter_and_value(call, name, value, tmp_path):
    with pytest.raises(ValueError, match=rf"`{name}`.*{value}"):
        call(tmp_path)
    assert list(tmp_path.iterdir()) == []          # nothing written


def test_cached_trials_bad_seed_writes_nothing(tmp_path):
    with pytest.raises(ValueError, match=r"`seed`.*-1"):
        cached_trials("generalized", 4, seed=-1, cache_dir=tmp_path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("damage", ["flip", "delete"])
def test_a_damaged_cache_block_is_regenerated_never_read(damage, tmp_path, small_blocks):
    """Flipped bytes in a chunk, or a deleted chunk (which zarr would read as zeros): the
    block's digests disagree, it is regenerated with a warning, and the trials returned
    are the true ones."""
    made = make_trials("generalized", 4, "train", 0)
    cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path)
    name = "inputs" if damage == "flip" else "position"
    (chunk,) = [p for p in tmp_path.glob(f"*/block000000.zarr/{name}/c/**/*") if p.is_file()]
    if damage == "flip":
        raw = bytearray(chunk.read_bytes())
        for k in range(4):
            raw[len(raw) // 2 + 7 * k] ^= 0xFF
        chunk.write_bytes(bytes(raw))
    else:
        chunk.unlink()
    with pytest.warns(RuntimeWarning, match="damaged"):
        got = cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path)
    assert_same_batch(got, made)
    # ... and the regenerated block is whole again
    assert_same_batch(cached_trials("generalized", 4, "train", 0, cache_dir=tmp_path), made)

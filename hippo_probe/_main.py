"""``hippo-probe main`` (the README's main job) and ``hippo-probe figures``.

Both call the figure builders of :mod:`hippo_probe.paper` in process and write under
their ``--out`` only; a clone's tracked copies (``paper_figures/png/*.png``,
``paper_figures/RESULTS.md``) are refreshed only by ``--refresh-tracked CLONE``, naming
the clone, and only from a run of every figure at the paper size (``bash quickstart.sh
main`` passes its own clone).
"""

import os
import shutil
import time
from contextlib import contextmanager

from ._cli_common import check_output, count, one_of

# the names only: the builders (matplotlib, torch) are imported when a command runs
from .paper import FIGURES

#: the worlds of the figures (hippo_probe.paper.config.WORLDS, without importing it)
WORLDS = ("darkness", "compass")


def add_commands(sub):
    sizes = ("tiny", "full", "paper")
    size_help = ("data size, per shipped run (a world's training seed), from scratch on 2 "
                 "quiet cores: full, 200 test trials, a few minutes in all; paper, the "
                 "study's scale: 1,000 test trials and PF-SLAM on 100, about 5 minutes "
                 "for a world's first run on one core and 2.1 for its others, which reuse "
                 "its reference filters (about 8 minutes for the four shipped runs, two "
                 "at once); "
                 "tiny, a smoke test of a handful of trials")
    cache_help = ("folder of the cached recordings, reused by later runs of the same size "
                  "(default: OUT/cache)")
    refresh_help = ("also copy the figures and RESULTS.md over the tracked copies of the "
                    "clone CLONE (CLONE/paper_figures/png/*.png, "
                    "CLONE/paper_figures/RESULTS.md); only with --size paper and every "
                    "figure")
    jobs_help = ("runs made at once, each in its own process with its share of the "
                 "cores (default: one per core, at most one per run; each holds its own "
                 "recordings in memory). The figures' numbers are the same; each run's "
                 "messages go to OUT/<run>/log.txt when N > 1")
    p = sub.add_parser("main", help="the README's main job: world statistics and every "
                                    "paper figure, into one folder")
    p.add_argument("--out", default="figures", metavar="FOLDER",
                   help="folder of the figures and their numbers")
    p.add_argument("--size", default="paper", choices=sizes, type=one_of("size", sizes),
                   help=size_help)
    p.add_argument("--cache", default=None, metavar="FOLDER", help=cache_help)
    p.add_argument("--refresh-tracked", default=None, metavar="CLONE", help=refresh_help)
    p.add_argument("--jobs", type=count(1), default=None, metavar="N", help=jobs_help)
    p.add_argument("--keep-cache", action="store_true",
                   help="keep the cached recordings (OUT/cache, about 3 GB a run at the "
                        "paper size) for a later run, or to rerun a failed job cheaply; by "
                        "default each run's are removed as soon as its figures are made, "
                        "and the rest (the first run's, which the network-vs-rodent "
                        "comparison reads, and each world's reference filters) when the "
                        "job ends; a --cache folder is never removed")
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    p.set_defaults(run=_main)
    f = sub.add_parser("figures", help="regenerate the paper figures and RESULTS.md into "
                                       "--out (nothing else is written)")
    f.add_argument("--out", default="figures", metavar="FOLDER",
                   help="folder of the figures, their numbers and RESULTS.md")
    f.add_argument("--size", default="full", choices=sizes, type=one_of("size", sizes),
                   help=size_help)
    f.add_argument("--only", nargs="*", choices=FIGURES, default=None, metavar="FIG",
                   type=one_of("only", FIGURES),
                   help=f"make only these figures, of {', '.join(FIGURES)} (default: all)")
    f.add_argument("--world", nargs="*", choices=WORLDS, default=None, metavar="WORLD",
                   type=one_of("world", WORLDS),
                   help=f"make the figures of these worlds' networks, of "
                        f"{', '.join(WORLDS)} (default: every world with shipped networks; "
                        f"each world's figures once per shipped training seed)")
    f.add_argument("--cache", default=None, metavar="FOLDER", help=cache_help)
    f.add_argument("--refresh-tracked", default=None, metavar="CLONE", help=refresh_help)
    f.add_argument("--jobs", type=count(1), default=None, metavar="N", help=jobs_help)
    f.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    f.set_defaults(run=_figures)


def _check_refresh(args):
    """Refuse --refresh-tracked, before any work, unless every figure runs at the paper
    size: the tracked copies show the study's scale, and a partial run would turn the
    other claims of RESULTS.md into "n/a"."""
    if args.refresh_tracked is None:
        return
    if args.size != "paper":
        raise ValueError(f"--refresh-tracked needs --size paper (the tracked copies show "
                         f"the study's scale); got --size {args.size}")
    if getattr(args, "only", None) is not None:
        raise ValueError("--refresh-tracked needs every figure; drop --only "
                         f"{' '.join(args.only)}")
    from .paper.tracked import check_repository

    check_repository(args.refresh_tracked)      # a clone to refresh, or one line now


def _refresh_of_main(args):
    """The clone ``main`` refreshes: ``--refresh-tracked``'s at the paper size; at another
    size none, said in one line (``bash quickstart.sh main --size tiny`` passes its clone
    whatever the size; ``figures`` refuses instead)."""
    if args.refresh_tracked is not None and args.size != "paper":
        print(f"(--size {args.size}: the tracked copies show the paper size; they are not "
              f"refreshed)")
        return None
    return args.refresh_tracked


def _figures(args, *, extra_tracked=(), drop_recordings=False):
    """``hippo-probe figures``; with ``drop_recordings`` (``main``, which removes the
    cache at the end) each run's cached recordings are removed as soon as its figures are
    made, except those the network-vs-rodent comparison reads, so that the runs do not all
    hold theirs on disk at once."""
    _check_refresh(args)
    out = check_output("--out", args.out, kind="folder")
    cache = out / "cache" if args.cache is None else check_output(
        "--cache", args.cache, kind="folder")
    from tqdm.auto import tqdm

    from ._atomic import write_text
    from .paper import config

    worlds = getattr(args, "world", None) or config.WORLDS
    runs = config.shipped_runs(worlds)
    if not runs:
        raise ValueError(f"no shipped networks of the world(s) {', '.join(worlds)}: "
                         f"`hippo-probe export-network` a trained run first")
    if args.refresh_tracked is not None and set(worlds) != set(config.WORLDS):
        raise ValueError("--refresh-tracked needs every world; drop --world")
    base = config.with_cache(config.CONFIGS[args.size], cache)
    # the figures of the first run (the darkness world's first seed once shipped) are the
    # ones shown; every run's are kept, and RESULTS.md and the ablation use them all
    cfgs = [config.for_run(base, world, seed) for world, seed in runs]
    t_all = time.time()
    names = args.only or FIGURES
    jobs = _jobs(getattr(args, "jobs", None), len(cfgs))
    tqdm.write(f"runs: {', '.join(cfg.run for cfg in cfgs)}"
               + (f" ({jobs} at once)" if jobs > 1 else ""))
    primary = cfgs[0]
    from .paper import rodent
    try:
        session = config.repository_file(rodent.SESSION, argument="session")
    except FileNotFoundError:
        if args.refresh_tracked is not None:
            raise
        session = None
        print(f"(no {rodent.SESSION}: the network-vs-rodent comparison runs from a clone)")
    # the comparison reads the first run's recording only: with several processes it
    # fills a core that would otherwise wait for the last run
    comparison = None if session is None else (primary.run, _network_vs_rodent,
                                               (primary, out, session))
    dropped = {cfg.run for cfg in cfgs if comparison is None or cfg is not primary} \
        if drop_recordings else set()
    timings = []                        # (run, figure, seconds), as the figures end
    with tqdm(total=len(cfgs) * len(names), desc="figures", unit="figure",
              disable=args.no_progress) as bar:
        def report(run, name, seconds):
            bar.update(1)
            tqdm.write(f"   {run}: {name} done in {seconds:.0f} s")
            timings.append((run, name, seconds))

        if jobs == 1:
            for cfg in cfgs:
                _make_run(cfg, names, out, report, echo=tqdm.write,
                          drop_cache=cfg.run in dropped)
            compared = None
        else:
            # a future, read where the comparison would run in turn: its failure stops
            # nothing before RESULTS.md is written
            compared = _make_runs_at_once(cfgs, names, out, report, jobs, then=comparison,
                                          dropped=dropped)
    order = {cfg.run: k for k, cfg in enumerate(cfgs)}
    timings.sort(key=lambda timing: order[timing[0]])
    write_text(out / "timings.md", _timings_table(timings, args.size, jobs,
                                                  time.time() - t_all), what="timings")
    shown = [out / primary.run / f"{name}.png" for name in names]
    from .paper.results import NOTES, write_results
    try:
        notes = config.repository_file(NOTES, argument="notes")
    except FileNotFoundError:
        if args.refresh_tracked is not None:
            raise
        notes = None
        print(f"(no {NOTES}: RESULTS.md without the notes; run from a clone for them)")
    made = [cfg.run for cfg in cfgs]       # not folders an earlier run left in --out
    print(f"wrote {write_results(out, out / 'RESULTS.md', notes, runs=made)}")
    from .paper import ablation
    shown.append(ablation.make(out, out, runs=made))
    if session is not None:
        print(f"== network vs rodent ({primary.run}) ==")
        if compared is None:
            rodent.make(primary, out, session=session)
        else:
            print(compared.result(), end="")
        shown.append(out / "network_vs_rodent.png")
    if args.refresh_tracked is not None:
        from .paper.tracked import refresh_tracked
        for path in refresh_tracked([*shown, *extra_tracked], out / "RESULTS.md",
                                    repository=args.refresh_tracked):
            print(f"refreshed {path}")
    print(f"all figures in {out}/ ({time.time() - t_all:.0f} s)")


def _jobs(requested: int | None, n_runs: int) -> int:
    """Processes for the runs: ``requested``, or one per usable core, never more than
    there are runs."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
        else (os.cpu_count() or 1)
    return max(1, min(requested or cores, n_runs))


def _make_run(cfg, names, out, report, echo=print, drop_cache=False):
    """Every figure ``names`` of the run ``cfg`` into ``out/<run>/``; ``report(run, name,
    seconds)`` after each; then, with ``drop_cache``, the run's cached recordings removed
    (not its world's reference filters, which the world's other runs read)."""
    from . import paper

    for name in names:
        t0 = time.time()
        echo(f"== {cfg.run}: {name} ({cfg.name}) ==")
        paper.builder(name).make(cfg, out / cfg.run)
        report(cfg.run, name, time.time() - t0)
    if drop_cache:
        shutil.rmtree(cfg.cache, ignore_errors=True)
        echo(f"   {cfg.run}: " + (f"could not remove all of its cached recordings "
                                  f"({cfg.cache})" if cfg.cache.exists() else
                                  f"removed its cached recordings ({cfg.cache})"))


#: Thread counts of the native libraries, read when they load: set for the workers before
#: they start (torch's OpenMP pool, once started, keeps spinning beside a second one).
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                    "NUMBA_NUM_THREADS")


def _huge_pages_for_malloc() -> str:
    """``GLIBC_TUNABLES`` for a worker whose large arrays glibc backs with transparent huge
    pages (where the kernel allows them on request; glibc 2.35 and later, ignored before).

    The figures allocate arrays of 0.1-0.5 GB again and again (the recordings' forward
    passes, the decoded chunks of cached recordings); on 4 KiB pages each is page-faulted
    in anew. A 750-trial recording after the first: 0.66 million page faults, 8.6-11.5 s;
    with huge pages 8,000 faults, 6.8-7.6 s. (Keeping freed blocks in the heap instead,
    as training does, made the main job faster still, 8 min 45 s against 9 min 06 s, but
    raised its peak memory from 4.0 to 7.1 GB.)
    Only spawned workers can be given it (glibc reads it at start): with ``--jobs 1``
    the figures run in this process without it.
    """
    tunables = [t for t in os.environ.get("GLIBC_TUNABLES", "").split(":") if t]
    if not any(t.startswith("glibc.malloc.hugetlb=") for t in tunables):
        tunables.append("glibc.malloc.hugetlb=1")
    return ":".join(tunables)


def _make_run_in_worker(cfg, names, out, queue, drop_cache=False):
    """:func:`_make_run` in a worker process (its threads set by :data:`THREAD_VARIABLES`),
    the run's messages and warnings into ``out/<run>/log.txt``, each figure's time onto
    ``queue``."""
    import contextlib

    (out / cfg.run).mkdir(parents=True, exist_ok=True)
    with open(out / cfg.run / "log.txt", "w") as log, contextlib.redirect_stdout(log), \
            contextlib.redirect_stderr(log):
        _make_run(cfg, names, out, lambda *timing: queue.put(timing), drop_cache=drop_cache)


@contextmanager
def _environment(**variables):
    """``os.environ`` with ``variables`` set, restored after (for spawned processes)."""
    before = {k: os.environ.get(k) for k in variables}
    os.environ.update(variables)
    try:
        yield
    finally:
        for k, v in before.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _interleave_worlds(cfgs):
    """The runs with each world's first before any world's second, and so on: the first
    run of a world makes the reference filters' estimates that its other runs reuse
    (:func:`~hippo_probe.paper.config.shared_arrays`), so while they are made, the runs
    made at once (as many as there are worlds, or fewer) are of different worlds rather
    than one waiting for another.

    >>> from types import SimpleNamespace as Run
    >>> runs = [Run(world=w, network_seed=k) for w, k in
    ...         [("darkness", 0), ("darkness", 1), ("darkness", 2), ("compass", 0)]]
    >>> [(r.world, r.network_seed) for r in _interleave_worlds(runs)]
    [('darkness', 0), ('compass', 0), ('darkness', 1), ('darkness', 2)]
    """
    rank, seen = {}, {}
    for k, cfg in enumerate(cfgs):
        rank[k] = seen.get(cfg.world, 0)
        seen[cfg.world] = rank[k] + 1
    return [cfgs[k] for k in sorted(range(len(cfgs)), key=lambda k: (rank[k], k))]


def _network_vs_rodent(primary, out, session) -> str:
    """:func:`hippo_probe.paper.rodent.make` in a worker; returns what it printed."""
    import contextlib
    import io

    from .paper import rodent

    printed = io.StringIO()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
        rodent.make(primary, out, session=session)
    return printed.getvalue()


def _make_runs_at_once(cfgs, names, out, report, jobs, then=None, dropped=frozenset()):
    """The runs in ``jobs`` processes (spawned: no state of this one is shared), the
    cores split evenly between them; a run that fails stops the others at once.

    ``then``, ``(run, function, arguments)`` or None: a task queued behind the runs once
    the run named ``run`` is done (it reads that run's recordings); returns its future
    (done; None without ``then``), whose error, unlike a run's, stops nothing. The runs
    named in ``dropped`` remove their cached recordings when done (:func:`_make_run`).
    """
    import multiprocessing
    import queue as queues
    from concurrent.futures import ProcessPoolExecutor

    threads = str(max(1, _jobs(None, 10 ** 6) // jobs))
    context = multiprocessing.get_context("spawn")
    with _environment(**dict.fromkeys(THREAD_VARIABLES, threads),
                      GLIBC_TUNABLES=_huge_pages_for_malloc()), \
            context.Manager() as manager:
        pool = ProcessPoolExecutor(jobs, mp_context=context)
        try:
            timings = manager.Queue()
            ordered = _interleave_worlds(cfgs)
            futures = [pool.submit(_make_run_in_worker, cfg, names, out, timings,
                                   cfg.run in dropped) for cfg in ordered]
            waited = None if then is None else \
                futures[[cfg.run for cfg in ordered].index(then[0])]
            extra = None

            def queue_then():
                nonlocal extra
                if extra is None and waited is not None and waited.done() \
                        and waited.exception() is None:
                    extra = pool.submit(then[1], *then[2])

            left = len(cfgs) * len(names)
            while left:
                try:
                    report(*timings.get(timeout=1.0))
                    left -= 1
                except queues.Empty:
                    failed = [f for f in futures if f.done() and f.exception() is not None]
                    if failed:
                        raise failed[0].exception()
                queue_then()
            for f in futures:
                f.result()
            queue_then()
        except BaseException:
            # the executor has no public way to stop a running task: without this, the
            # other runs would go on (minutes to hours) before the error is shown
            for process in list(getattr(pool, "_processes", {}).values()):
                process.terminate()
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown()                 # waits for ``extra`` too
    return extra


def _timings_table(timings, size, jobs, wall_s) -> str:
    """The seconds each figure of each run took, as a Markdown table."""
    runs = list(dict.fromkeys(run for run, _, _ in timings))
    names = list(dict.fromkeys(name for _, name, _ in timings))
    took = {(run, name): s for run, name, s in timings}
    lines = [f"# Time per figure (size {size}, {jobs} run(s) at once)", "",
             "Seconds per figure; the first figure of a run to need a recording makes it.",
             "", "| run | " + " | ".join(names) + " | total |",
             "|---" * (len(names) + 2) + "|"]
    for run in runs:
        row = [took.get((run, name), float("nan")) for name in names]
        lines.append(f"| {run} | " + " | ".join(f"{s:.0f}" for s in row)
                     + f" | {sum(row):.0f} |")
    lines += ["", f"Wall time of the figures: {wall_s:.0f} s.", ""]
    return "\n".join(lines)


def _main(args):
    out = check_output("--out", args.out, kind="folder")
    if args.cache is not None:
        check_output("--cache", args.cache, kind="folder")
    args.refresh_tracked = _refresh_of_main(args)
    _check_refresh(args)
    from ._atomic import save_figure
    from .trial_stats import format_stats, plot_example_trials, world_stats

    out.mkdir(parents=True, exist_ok=True)
    print("== World statistics (500 test trials per task) ==")
    print(format_stats(world_stats(n_trials=500)))
    fig = plot_example_trials()
    save_figure(fig, out / "example_trials.png", dpi=120)
    print(f"saved {out / 'example_trials.png'}")
    remove = args.cache is None and not args.keep_cache
    _figures(args.__class__(out=args.out, size=args.size, only=None, cache=args.cache,
                            refresh_tracked=args.refresh_tracked, world=None,
                            jobs=args.jobs, no_progress=args.no_progress),
             extra_tracked=(out / "example_trials.png",), drop_recordings=remove)
    if remove:
        shutil.rmtree(out / "cache", ignore_errors=True)
        if (out / "cache").exists():
            print(f"could not remove all of the cached recordings in {out / 'cache'}")
        else:
            print(f"removed the cached recordings ({out / 'cache'}; --keep-cache keeps "
                  f"them)")

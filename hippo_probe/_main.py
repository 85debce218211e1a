"""``hippo-probe main`` (the README's main job) and ``hippo-probe figures``."""

import time
from pathlib import Path

from .cli import check_output, one_of

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ("fig2", "fig3", "fig4", "fig5")


def add_commands(sub):
    sizes = ("tiny", "full", "paper")
    size_help = ("data size: full, 200 test trials, about 2 minutes from scratch on 2 cores; "
                 "paper, the study's scale: 1,000 test trials and PF-SLAM on 100 (about 4 "
                 "minutes); tiny, a smoke test")
    p = sub.add_parser("main", help="the README's main job: world statistics and every "
                                    "paper figure, into one folder")
    p.add_argument("--out", default="figures", metavar="FOLDER",
                   help="folder of the figures and their numbers")
    p.add_argument("--size", default="paper", choices=sizes, type=one_of("size", sizes),
                   help=size_help)
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    p.set_defaults(run=_main)
    f = sub.add_parser("figures", help="regenerate the paper figures and RESULTS.md")
    f.add_argument("--out", default="figures", metavar="FOLDER",
                   help="folder of the figures and their numbers")
    f.add_argument("--size", default="full", choices=sizes, type=one_of("size", sizes),
                   help=size_help)
    f.add_argument("--only", nargs="*", choices=FIGURES, default=None, metavar="FIG",
                   type=one_of("only", FIGURES),
                   help=f"make only these figures, of {', '.join(FIGURES)} (default: all)")
    f.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    f.set_defaults(run=_figures)


def _load(name):
    """Import a script of paper_figures/ (by its file name) as a module."""
    import importlib
    import sys

    folder = ROOT / "paper_figures"
    if not (folder / f"{name}.py").exists():
        raise FileNotFoundError(f"{folder / name}.py not found: `hippo-probe figures` runs "
                                f"from a clone of the repository (the figure scripts are "
                                f"not package data)")
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
    return importlib.import_module(name)


def _figures(args):
    from tqdm.auto import tqdm

    out = check_output("--out", args.out, kind="folder")
    common = _load("_common")
    cfg = common.CONFIGS[args.size]
    t_all = time.time()
    names = args.only or FIGURES
    with tqdm(names, desc="figures", unit="figure", disable=args.no_progress) as bar:
        for name in bar:
            t0 = time.time()
            bar.set_postfix_str(name)
            tqdm.write(f"== {name} ({args.size}) ==")
            _load(name).make(cfg, out)
            tqdm.write(f"   {name} done in {time.time() - t0:.0f} s")
    results = _load("results")
    import sys
    argv = sys.argv
    # the repository's RESULTS.md only from full-size data; other sizes write beside
    # their figures
    table = (ROOT / "paper_figures" / "RESULTS.md") if args.size in ("full", "paper") \
        else out / "RESULTS.md"
    sys.argv = ["results.py", "--figures", str(out), "--out", str(table)]
    try:
        results.main()
    finally:
        sys.argv = argv
    comparison = ROOT / "analyses" / "network_vs_rodent.py"
    if comparison.exists():
        print("== network vs rodent ==")
        import subprocess
        subprocess.run([sys.executable, str(comparison), "--size", args.size, "--out",
                        str(out)], check=True)
    if args.size in ("full", "paper"):
        _update_readme_images(out)
    print(f"all figures in {out}/ ({time.time() - t_all:.0f} s)")


def _update_readme_images(out):
    """Refresh the README's copies (paper_figures/png/) of the figures just made, like
    RESULTS.md: the repository shows what its own networks give."""
    import shutil

    shown = ROOT / "paper_figures" / "png"
    if not shown.is_dir():
        return
    for old in shown.glob("*.png"):
        new = Path(out) / old.name
        if new.exists():
            shutil.copyfile(new, old)


def _main(args):
    from ._atomic import save_figure
    from .world.stats import format_stats, plot_example_trials, world_stats

    out = check_output("--out", args.out, kind="folder")
    out.mkdir(parents=True, exist_ok=True)
    print("== World statistics (500 test trials per task) ==")
    print(format_stats(world_stats(n_trials=500)))
    fig = plot_example_trials()
    save_figure(fig, out / "example_trials.png", dpi=120)
    print(f"saved {out / 'example_trials.png'}")
    _figures(args.__class__(out=args.out, size=args.size, only=None,
                            no_progress=args.no_progress))

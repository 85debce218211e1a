"""Figure 2: localization in a familiar arena (mean radius 1 m), start unknown.

A thin entry point: the figure is built by :mod:`hippo_probe.paper.fig2` (its
``make(config, out)``), as ``hippo-probe figures --only fig2`` does.

    python paper_figures/fig2.py [--size tiny|full|paper] [--out figures/]
"""

from _common import parse_args

from hippo_probe.paper import fig2

if __name__ == "__main__":
    fig2.make(*parse_args(__doc__.splitlines()[0]))

"""Figure 5: what the population encodes beyond position.

A thin entry point: the figure is built by :mod:`hippo_probe.paper.fig5` (its
``make(config, out)``), as ``hippo-probe figures --only fig5`` does.

    python paper_figures/fig5.py [--size tiny|full|paper] [--out figures/]
"""

from _common import parse_args

from hippo_probe.paper import fig5

if __name__ == "__main__":
    fig5.make(*parse_args(__doc__.splitlines()[0]))

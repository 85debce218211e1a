"""Figure 4: the networks' units recorded like cells.

A thin entry point: the figure is built by :mod:`hippo_probe.paper.fig4` (its
``make(config, out)``), as ``hippo-probe figures --only fig4`` does.

    python paper_figures/fig4.py [--size tiny|full|paper] [--out figures/]
"""

from _common import parse_args

from hippo_probe.paper import fig4

if __name__ == "__main__":
    fig4.make(*parse_args(__doc__.splitlines()[0]))

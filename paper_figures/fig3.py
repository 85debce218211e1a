"""Figure 3: novel arenas, the arena classifier, PF-SLAM and readout retraining.

A thin entry point: the figure is built by :mod:`hippo_probe.paper.fig3` (its
``make(config, out)``), as ``hippo-probe figures --only fig3`` does.

    python paper_figures/fig3.py [--size tiny|full|paper] [--out figures/]
"""

from _common import parse_args

from hippo_probe.paper import fig3

if __name__ == "__main__":
    fig3.make(*parse_args(__doc__.splitlines()[0]))

"""Write paper_figures/RESULTS.md: each quantitative claim of the study beside our value.

Reads the JSON files the figure scripts wrote (``figures/fig*.json``). A thin entry point
over :func:`hippo_probe.paper.results.write_results`, which ``hippo-probe figures`` calls.

    python paper_figures/results.py [--figures figures/] [--out paper_figures/RESULTS.md]
"""

import argparse
import sys
from pathlib import Path

from hippo_probe.paper.results import write_results

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figures", default=str(ROOT / "figures"))
    ap.add_argument("--out", default=str(ROOT / "paper_figures" / "RESULTS.md"))
    ap.add_argument("--notes", default=str(ROOT / "paper_figures" / "RESULTS_notes.md"),
                    help="hand-written explanations appended to the table")
    a = ap.parse_args()
    try:
        print(f"wrote {write_results(a.figures, a.out, a.notes)}")
    except (ValueError, FileNotFoundError) as err:
        sys.exit(f"{Path(__file__).name}: error: {err}")


if __name__ == "__main__":
    main()

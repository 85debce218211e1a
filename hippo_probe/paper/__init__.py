"""The paper's figures: one builder per figure, the RESULTS.md writer, the tracked copies.

Every figure builder is a module with one entry point, the contract of this package::

    make(config: FigureConfig, out: str | os.PathLike) -> dict

It draws the figure from recordings of the shipped networks at the sizes of ``config``
(:data:`hippo_probe.paper.config.CONFIGS`: ``tiny``, ``full``, ``paper``), writes
``<out>/<name>.png``, ``.pdf`` and ``.json`` and returns the numbers it wrote to the
JSON. It writes nothing outside ``out`` unless ``config`` names a cache folder elsewhere
(:func:`~hippo_probe.paper.config.with_cache`; the default cache is ``<out>/cache``).

A configuration names a run: the networks of one world trained with one seed
(``config.world``, ``config.network_seed``); ``hippo-probe figures`` makes every figure
once per shipped run (:func:`~hippo_probe.paper.config.shipped_runs`) into
``<out>/<world>-seed<k>/``.

Modules: :mod:`~hippo_probe.paper.fig2` ... :mod:`~hippo_probe.paper.fig5` (the study's
Figs. 2-5), :mod:`~hippo_probe.paper.rodent` (network units vs mouse cells, same
contract, plus the NWB session's path), :mod:`~hippo_probe.paper.results`
(``write_results``: RESULTS.md from every run's figure JSON, a column per world with the
spread over seeds), :mod:`~hippo_probe.paper.ablation` (each claim's numbers in the two
worlds, one point per seed; ``make(figures_dir, out)``) and
:mod:`~hippo_probe.paper.tracked` (``refresh_tracked``: the repository's copies,
``paper_figures/png/*.png`` and ``paper_figures/RESULTS.md``).

Examples
--------
>>> from hippo_probe.paper import FIGURES, config
>>> FIGURES
('fig2', 'fig3', 'fig4', 'fig5')
>>> config.CONFIGS["tiny"].trials
4
"""

#: The study's figures, each a module of this package with ``make(config, out)``.
FIGURES = ("fig2", "fig3", "fig4", "fig5")


def builder(name: str):
    """The module of figure ``name`` (one of :data:`FIGURES`, or ``"rodent"``)."""
    import importlib

    from .._validators import check_option

    check_option("figure", name, (*FIGURES, "rodent"))
    return importlib.import_module(f"{__name__}.{name}")

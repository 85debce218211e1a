"""What is shipped, and how its training seeds spread: read from the training logs
(``<name>[_seed<k>].log.json``) beside the networks, so it needs no torch.

The test metrics are the trainer's, on the task's 1,000-trial test split of the network's
world (``hippo-probe train`` ends each run with them); the figures measure again on their
own recordings (``paper_figures/RESULTS.md``).
"""

from __future__ import annotations

import json
from pathlib import Path

from .._validators import check_nonnegative_int
from . import HERE, NAMES, checkpoint_world, shipped_seeds

#: Test metrics reported per network: error (m) and arena accuracy at 50 / 100 / 200 s.
METRICS = ("error_50s_m", "error_100s_m", "error_200s_m",
           "accuracy_50s", "accuracy_100s", "accuracy_200s")


def _log_file(folder: Path, name: str, seed: int) -> Path:
    return folder / (f"{name}.log.json" if seed == 0 else f"{name}_seed{seed}.log.json")


def training_log(name: str, seed: int = 0, *, folder=None) -> dict:
    """The training log of a shipped network: its config, command, training and
    validation curves (``log["validation"]``: one entry per validation, with ``step`` and
    ``mean_error_m``), resumes and test metrics.

    Parameters
    ----------
    name : str
        A shipped network's name (``hippo-probe networks`` lists them).
    seed : int
        Its training seed.
    folder : str or os.PathLike, optional
        Folder of the shipped files (default: the package's).

    Raises
    ------
    ValueError
        The network is not shipped at that seed, or its log cannot be read.

    Examples
    --------
    >>> from hippo_probe.pretrained.summary import training_log
    >>> curve = training_log("generalized_faithful")["validation"]
    >>> curve[0]["step"], curve[-1]["step"]
    (0, 20000)
    """
    if name not in NAMES:
        raise ValueError(f"`name` must be a shipped network's name (one of {list(NAMES)}); "
                         f"got {name!r}")
    seed = check_nonnegative_int("seed", seed)
    folder = HERE if folder is None else Path(folder)
    seeds = shipped_seeds(name, folder=folder)
    if seed not in seeds:
        raise ValueError(f"`seed` {seed} of {name!r} is not shipped; shipped seeds: "
                         f"{seeds or 'none'}")
    path = _log_file(folder, name, seed)
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as err:
        raise ValueError(f"the training log of {name!r} seed {seed} ({path}) cannot "
                         f"be read: {err}") from None


def shipped_table(names=NAMES, *, folder=None):
    """One row per shipped network and training seed: its world, training and test metrics.

    Parameters
    ----------
    names : iterable of str, optional
        Network names (default: every name of :data:`NAMES`; unshipped ones are skipped).
    folder : str or os.PathLike, optional
        Folder of the shipped files (default: the package's).

    Returns
    -------
    pandas.DataFrame
        Index (``network``, ``seed``); columns ``world``, ``variant`` (``"faithful"``, the
        study's network, or the departure it was trained as), ``steps``, ``budget``,
        ``stopped_early`` (the 1% rule ended it before its budget), ``hours`` (wall time of
        training) and :data:`METRICS` (NaN where the task has no arena class). A readout
        fitted as a convex problem (its log has ``fit``) has 0 steps and no budget.

    Examples
    --------
    >>> from hippo_probe.pretrained.summary import shipped_table
    >>> table = shipped_table(["localization"])
    >>> table.index.names
    FrozenList(['network', 'seed'])
    """
    import pandas as pd

    folder = HERE if folder is None else Path(folder)
    rows = []
    for name in names:
        for seed in shipped_seeds(name, folder=folder):
            log = training_log(name, seed, folder=folder)
            # a readout fitted as a convex problem (log["fit"]) took no gradient steps
            steps = (log.get("stopped") or {}).get("step") or max(
                (v["step"] for v in log.get("validation", [])), default=0)
            test = log.get("test") or {}
            rows.append({"network": name, "seed": seed, "world": checkpoint_world(log),
                         "variant": log["config"].get("variant") or "faithful",
                         "steps": steps, "budget": log["config"]["steps"],
                         "stopped_early": bool(log.get("stopped")),
                         "hours": (log.get("wall_time_s") or float("nan")) / 3600,
                         **{m: test.get(m, float("nan")) for m in METRICS}})
    columns = ["network", "seed", "world", "variant", "steps", "budget", "stopped_early",
               "hours", *METRICS]
    return pd.DataFrame(rows, columns=columns).set_index(["network", "seed"])


def spread_text(values, digits: int) -> str:
    """Values over seeds as text: ``mean (min–max)``, the value alone for one seed, "—"
    for none."""
    if not values:
        return "—"
    if len(values) == 1:
        return f"{values[0]:.{digits}f}"
    return (f"{sum(values) / len(values):.{digits}f} ({min(values):.{digits}f}–"
            f"{max(values):.{digits}f})")


def seed_spread(table):
    """Per network: the number of seeds and each metric as ``mean (min–max)`` over them.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`shipped_table`'s output.

    Returns
    -------
    pandas.DataFrame
        Index ``network``; columns ``world``, ``variant``, ``seeds`` (which are shipped)
        and one text column per metric with a value ("—" where the task has none).
    """
    import pandas as pd

    out = {}
    for name, rows in table.groupby(level="network", sort=False):
        entry = {"world": rows["world"].iloc[0], "variant": rows["variant"].iloc[0],
                 "seeds": ", ".join(str(s) for s in rows.index.get_level_values("seed"))}
        for metric in METRICS:
            entry[metric] = spread_text(rows[metric].dropna().tolist(),
                                        3 if metric.startswith("error") else 2)
        out[name] = entry
    frame = pd.DataFrame.from_dict(out, orient="index")
    frame.index.name = "network"
    return frame


def per_seed_text(table) -> str:
    """:func:`shipped_table` as aligned text: errors in m to the mm, accuracies to two
    digits, hours to one, and "—" where a network has no such value (no arena readout,
    or a readout fitted without a step budget)."""
    formats = {m: ("{:.3f}" if m.startswith("error") else "{:.2f}").format for m in METRICS}
    formats.update(hours="{:.1f}".format, budget="{:.0f}".format)
    return table.to_string(formatters=formats, na_rep="—")


def markdown(spread) -> str:
    """:func:`seed_spread` as a Markdown table (errors in m, at 50 / 100 / 200 s)."""
    head = ["network", "world", "seeds", "error 50 / 100 / 200 s (m)",
            "arena accuracy 50 / 100 / 200 s"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, r in spread.iterrows():
        errors = " / ".join(r[m] for m in METRICS[:3])
        accuracy = " / ".join(r[m] for m in METRICS[3:])
        if r.get("variant", "faithful") != "faithful":       # a departure says so
            name = f"{name} ({r['variant']} variant, a departure)"
        lines.append(f"| {name} | {r['world']} | {r['seeds']} | {errors} | "
                     f"{'—' if set(accuracy.split(' / ')) == {'—'} else accuracy} |")
    return "\n".join(lines)

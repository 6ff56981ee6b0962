"""The journal, the runs table, the summary and its figures."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from tt_mujoco.outputs import (
    JsonField,
    check_fields,
    parse_strict_json,
    read_regular,
    save_figure,
    shown_json,
)
from tt_mujoco.sweep.options import (
    KEY_METRICS,
    PERCENTILES,
    RESULT_COLUMNS,
    WALL_COLUMNS,
    BadSpecError,
)
from tt_mujoco.sweep.runs import config_columns
from tt_mujoco.sweep.spec import SweepSpec

# --- journal and table -------------------------------------------------------------------------
_SCALARS = (str, int, float, bool, type(None))
#: A journal record, as the sweep writes one per finished run (:func:`read_journal`).
JOURNAL_FIELDS = (
    JsonField("run_id", (str,), "a string (the run's id)", required=True),
    JsonField("index", (int,), "a whole number >= 0 (the run's place)", required=True),
    JsonField("status", (str,), "a string (ok, jackknife, diverged, error, ...)", required=True),
    JsonField("message", (str,), "a string"),
    JsonField("error", (str,), "a string"),
    JsonField("metrics", (dict,), "a table of the run's metrics", required=True),
    JsonField("config", (dict,), "a table of the run's configuration"),
    JsonField("run_wall_s", (int, float, type(None)), "a number of seconds or null"),
)


def _record_problem(record) -> str:
    """Why ``record`` is not a journal record, or ""."""
    if not isinstance(record, dict):
        return f"it holds {shown_json(record)}, not a run's record (a table)"
    why = check_fields(record, JOURNAL_FIELDS)
    if why:
        return why
    for table in ("metrics", "config"):
        for name, value in record.get(table, {}).items():
            if not isinstance(value, _SCALARS):
                return f"{table}.{name} holds {shown_json(value)}, not a number, text or null"
    return ""


def read_journal(path: Path) -> dict[str, dict]:
    """Finished runs by run_id, each line checked against :data:`JOURNAL_FIELDS`.

    Only the last line may be cut (a kill while it was written: no newline after it, not
    JSON): it is dropped and that run runs again. Any other line that is not a run's record is
    damage, refused naming the line and the field.

    Raises
    ------
    BadSpecError
        A damaged line: ``journal.jsonl line N: ...`` (exit code 2).
    """
    done = {}
    try:
        data = read_regular(path, str(path))
    except FileNotFoundError:
        return done
    except ValueError as err:
        raise BadSpecError(str(err)) from None
    lines = data.split(b"\n")
    for number, raw in enumerate(lines, start=1):
        if not raw.strip():
            continue
        try:
            record = parse_strict_json(raw.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as err:
            if number == len(lines):  # no newline after it: cut by a kill
                continue
            reason = "not UTF-8 text" if isinstance(err, UnicodeDecodeError) else str(err)
            raise BadSpecError(
                f"{path} line {number} is not a run's record ({reason}): remove that line to "
                "run that run again"
            ) from None
        why = _record_problem(record)
        if why:
            raise BadSpecError(
                f"{path} line {number}: {why}; remove that line to run that run again"
            )
        done[record["run_id"]] = record
    return done


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)  # full precision: tables from any executor compare exactly
    return str(value)


def _config_of(run: Mapping, record: Mapping) -> dict:
    """A row's configuration: as the run's journal record kept it, else resolved now, else
    (a file the run read is gone) the options as given."""
    kept = record.get("config")
    if not (isinstance(kept, dict) and kept):
        try:
            return config_columns(run)
        except (ValueError, OSError):
            kept = run["options"]
    return {"index": run["index"], "run_id": run["run_id"], "replicate": run["replicate"], **kept}


def build_rows(runs: Sequence[dict], done: Mapping[str, dict]) -> tuple[list[str], list[dict]]:
    """The table: header and one row per run (in run order) from the journal's records."""
    rows = []
    config_names: list[str] = []
    metric_names: list[str] = []
    for run in runs:
        record = done[run["run_id"]]
        row = _config_of(run, record)
        for name in row:
            if name not in config_names:
                config_names.append(name)
        row.update({k: record.get(k, "") for k in RESULT_COLUMNS})
        for name, value in record.get("metrics", {}).items():
            if name not in metric_names and name not in WALL_COLUMNS:
                metric_names.append(name)
            row[name] = value
        row["run_wall_s"] = record.get("run_wall_s")
        rows.append(row)
    header = config_names + list(RESULT_COLUMNS) + metric_names + list(WALL_COLUMNS)
    return header, rows


def table_csv(header: Sequence[str], rows: Sequence[Mapping]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    for row in rows:
        writer.writerow([_cell(row.get(name)) for name in header])
    return buf.getvalue()


def read_table(path: str | Path) -> list[dict[str, str]]:
    """A ``runs.csv`` as a list of rows (column -> text; empty text for missing values)."""
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


# --- summary and figures -------------------------------------------------------------------------
def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _numeric(rows: Sequence[Mapping], name: str) -> np.ndarray:
    """Column ``name`` as floats, NaN where a row has no number."""
    return np.array([float(v) if _is_number(v := r.get(name)) else math.nan for r in rows])


def group_options(spec: SweepSpec, rows: Sequence[Mapping]) -> list[str]:
    """The categorical options that vary (controller, target, plant, path, ...): their values
    are text, and pooling their groups' metrics would put a median between populations."""
    names = [a.name for a in spec.axes if a.varies and a.name != "seed"]
    return [n for n in names if not _is_numeric(rows, n) and len({r.get(n) for r in rows}) > 1]


def group_of(row: Mapping, options: Sequence[str]) -> str:
    """A row's group label, e.g. ``controller=pid, target=static``."""
    return ", ".join(f"{name}={row.get(name)}" for name in options)


def _statistics(header: Sequence[str], rows: Sequence[Mapping]) -> dict:
    ok_rows = [r for r in rows if r["status"] == "ok"]
    start = header.index("error") + 1
    stats = {}
    for name in header[start:]:
        if not any(_is_number(r.get(name)) for r in rows):
            continue  # a text column (e.g. a fault's kind)
        x = _numeric(ok_rows, name)
        x = x[np.isfinite(x)]
        entry = {"n": int(x.size)}
        if x.size:
            entry.update(mean=float(x.mean()), std=float(x.std()), min=float(x.min()))
            for p, v in zip(PERCENTILES, np.percentile(x, PERCENTILES), strict=True):
                entry[f"p{p}"] = float(v)
            entry["max"] = float(x.max())
        stats[name] = entry
    return stats


def summarize(header: Sequence[str], rows: Sequence[Mapping], group_by: Sequence[str] = ()) -> dict:
    """Counts by status and, per metric, statistics over the runs that finished ``ok``.

    Metrics of stopped runs cover only the time before the stop, so they would mix two
    populations; their number is in ``failed`` and ``by_status`` instead.

    Returns
    -------
    dict
        ``runs``, ``ok``, ``failed``, ``by_status`` (status -> count), ``errors`` (the first 5
        distinct error texts), ``metrics`` (name -> ``n``, ``mean``, ``std``, ``min``,
        ``p5``...``p95``, ``max``; NaN values skipped); with ``group_by`` (categorical
        options, :func:`group_options`) also ``groups``: label -> the same per group.
    """
    by_status: dict[str, int] = {}
    for row in rows:
        by_status[row["status"]] = by_status.get(row["status"], 0) + 1
    ok_rows = [r for r in rows if r["status"] == "ok"]
    errors = list(dict.fromkeys(r["error"] for r in rows if r.get("error")))[:5]
    stats = _statistics(header, rows)
    groups = {}
    for label in dict.fromkeys(group_of(r, group_by) for r in rows) if group_by else ():
        members = [r for r in rows if group_of(r, group_by) == label]
        groups[label] = {
            "runs": len(members),
            "ok": sum(r["status"] == "ok" for r in members),
            "metrics": _statistics(header, members),
        }
    return {
        "group_by": list(group_by),
        "groups": groups,
        "runs": len(rows),
        "ok": len(ok_rows),
        "failed": len(rows) - len(ok_rows),
        "by_status": dict(sorted(by_status.items())),
        "errors": errors,
        "metrics": stats,
    }


def summary_csv(summary: Mapping) -> str:
    """One row per metric over all runs (group ``all``), then per metric and group."""
    keys = ["n", "mean", "std", "min", *(f"p{p}" for p in PERCENTILES), "max"]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["group", "metric", *keys])
    parts = [("all", summary["metrics"])]
    parts += [(label, g["metrics"]) for label, g in summary.get("groups", {}).items()]
    for label, metrics in parts:
        for name, entry in metrics.items():
            writer.writerow([label, name, *(_cell(entry.get(k)) for k in keys)])
    return buf.getvalue()


def summary_text(summary: Mapping, metric_names: Sequence[str]) -> str:
    lines = [
        f"{summary['runs']} runs: {summary['ok']} ok, {summary['failed']} failed"
        + "".join(
            f", {count} {status}"
            for status, count in summary["by_status"].items()
            if status != "ok"
        )
    ]
    width = max([len(n) for n in metric_names] + [6])
    lines.append(f"{'metric':<{width}}  {'p5':>10} {'median':>10} {'p95':>10} {'max':>10}")
    for name in metric_names:
        e = summary["metrics"].get(name, {})
        if not e.get("n"):
            continue
        lines.append(
            f"{name:<{width}}  {e['p5']:>10.4g} {e['p50']:>10.4g} {e['p95']:>10.4g} "
            f"{e['max']:>10.4g}"
        )
    for label, group in summary.get("groups", {}).items():
        lines.append(f"{label}: {group['ok']} of {group['runs']} ok")
        for name in metric_names:
            e = group["metrics"].get(name, {})
            if e.get("n"):
                lines.append(
                    f"  {name:<{width}}  {e['p5']:>10.4g} {e['p50']:>10.4g} {e['p95']:>10.4g} "
                    f"{e['max']:>10.4g}"
                )
    for err in summary["errors"]:
        lines.append(f"error: {err}")
    return "\n".join(lines)


def labelled(name: str) -> str:
    """An axis label: a metric's or an option's name with its unit, ``rmse_lateral [m]``
    (a gain, a count or a user's metric: the name alone)."""
    from tt_mujoco.analysis.metrics import metric_unit
    from tt_mujoco.sim.scenario import SCHEMA

    unit = metric_unit(name)
    if unit is None and name in SCHEMA.names:
        unit = SCHEMA[name].unit
    return f"{name} [{unit}]" if unit else name


def _suptitle(fig, text: str) -> None:
    """A figure's title, wrapped to the figure's width (a long one was clipped at its sides)."""
    import textwrap

    width_in = fig.get_size_inches()[0]
    fig.suptitle(textwrap.fill(text, width=max(30, int(width_in * 10))))


class _Groups(NamedTuple):
    """How a sweep's figures colour its runs: the categorical options that vary (``by``),
    each group's label in order and its colour."""

    by: tuple
    labels: list
    colour: dict

    def members(self, rows: Sequence[Mapping], label: str) -> np.ndarray:
        """Which of ``rows`` are in the group ``label`` (every run, without groups)."""
        return np.array([not self.by or group_of(r, self.by) == label for r in rows])


def plot_summary(
    rows: Sequence[Mapping], spec: SweepSpec, out: Path, metric: str = "rmse_lateral"
) -> list[Path]:
    """``histograms.png`` (key metrics over the ok runs) and ``scatter.png`` (``metric``
    against each numeric option that varies; failed runs drawn as red crosses at the top). Runs
    are coloured by group when categorical options vary (:func:`group_options`): a pooled
    histogram or median would fall between populations."""
    by = group_options(spec, rows)
    labels = list(dict.fromkeys(group_of(r, by) for r in rows)) if by else [""]
    groups = _Groups(by, labels, {label: f"C{i % 10}" for i, label in enumerate(labels)})
    return [_histograms(rows, groups, metric, out), _scatter(rows, spec, groups, metric, out)]


def _histograms(rows: Sequence[Mapping], groups: _Groups, metric: str, out: Path) -> Path:
    """``histograms.png``: the key metrics and ``metric`` over the ok runs, per group."""
    from matplotlib.figure import Figure  # matplotlib only for sweeps that draw figures

    ok = [r for r in rows if r["status"] == "ok"]
    by, colour = groups.by, groups.colour
    names = [m for m in dict.fromkeys([*KEY_METRICS, metric]) if np.isfinite(_numeric(ok, m)).any()]
    names = names[:6]
    fig = Figure(figsize=(12, 6.5), layout="constrained")
    axs = fig.subplots(2, 3, squeeze=False).ravel()
    for ax, name in zip(axs, names, strict=False):
        x = _numeric(ok, name)
        x = x[np.isfinite(x)]
        bins = np.histogram_bin_edges(x, bins=min(40, max(5, int(math.sqrt(x.size)) + 1)))
        for label in groups.labels:
            xg = _numeric([r for r in ok if not by or group_of(r, by) == label], name)
            xg = xg[np.isfinite(xg)]
            if xg.size:
                med = float(np.median(xg))
                tag = f"{label}: median {med:.3g}" if by else f"median {med:.3g}"
                ax.hist(xg, bins=bins, color=colour[label], alpha=0.55 if by else 0.8, label=tag)
                ax.axvline(med, color=colour[label] if by else "k", lw=1, ls="--")
        ax.set_xlabel(labelled(name))
        ax.set_ylabel("runs")
        ax.legend(fontsize=8)
    for ax in axs[len(names) :]:
        ax.set_visible(False)
    failed = len(rows) - len(ok)
    _suptitle(fig, f"{len(rows)} runs: {len(ok)} ok, {failed} failed (histograms of ok runs)")
    return save_figure(fig, out / "histograms.png", 120)


def _scatter(
    rows: Sequence[Mapping], spec: SweepSpec, groups: _Groups, metric: str, out: Path
) -> Path:
    """``scatter.png``: ``metric`` against each numeric option that varies (two metrics
    against each other where none does)."""
    from matplotlib.figure import Figure

    axes = [a for a in spec.axes if a.varies and a.name != "seed" and _is_numeric(rows, a.name)]
    axes = axes[:6]
    y_all = _numeric(rows, metric)
    bad = np.array([r["status"] != "ok" for r in rows])
    finite = y_all[~bad & np.isfinite(y_all)]
    top = float(finite.max()) * 1.05 if finite.size else 1.0
    failed = int(bad.sum())
    if axes:
        n_rows, n_cols = math.ceil(len(axes) / 3), min(3, len(axes))
        fig = Figure(figsize=(4.2 * n_cols, 3.6 * n_rows), layout="constrained")
        panels = fig.subplots(n_rows, n_cols, squeeze=False).ravel()
        # Fixed jitter spreads the runs of a grid value sideways (the same picture every time).
        jitter = np.random.default_rng(0).uniform(-1.0, 1.0, len(rows))
        for ax, axis in zip(panels, axes, strict=False):
            _scatter_panel(ax, axis.name, rows, groups, (y_all, bad, top), jitter)
            ax.set_ylabel(labelled(metric))
        for ax in panels[len(axes) :]:
            ax.set_visible(False)
        title = (
            f"{metric} per run ({failed} failed runs drawn at the top in red; lines: median per "
            f"value{' and group' if groups.by else ''})"
        )
    else:  # nothing numeric varies (e.g. seeds only): two metrics against each other
        fig = Figure(figsize=(5.5, 4.5), layout="constrained")
        ax = fig.subplots()
        other = "rmse_v" if metric != "rmse_v" else "rmse_omega"
        x_all = _numeric(rows, other)
        ax.scatter(x_all[~bad], y_all[~bad], s=12, alpha=0.6, color="tab:blue")
        ax.set_xlabel(labelled(other))
        ax.set_ylabel(labelled(metric))
        title = f"{metric} per run ({failed} failed runs not drawn)"
    _suptitle(fig, title)
    return save_figure(fig, out / "scatter.png", 120)


def _scatter_panel(ax, name: str, rows, groups: _Groups, metric_of, jitter) -> None:
    """One option's panel: the runs (jittered where the option takes few values, with each
    value's median per group), the failed ones at the top. ``metric_of``: the metric of every
    run, which failed, and the top."""
    y_all, bad, top = metric_of
    x = np.array([float(r[name]) for r in rows])
    log = bool(np.all(x > 0) and x.max() >= 10 * x.min())
    if log:
        ax.set_xscale("log")
    u = np.log(x) if log else x  # jitter and medians where the axis is uniform
    levels = np.unique(u)
    xs = x
    if 1 < levels.size <= 12:
        half = 0.3 * float(np.diff(levels).min())
        u_jit = u + 0.5 * half * jitter
        xs = np.exp(u_jit) if log else u_jit
        for level in levels:  # the median of the ok runs at each value, per group
            ends = np.array([level - half, level + half])
            ends = np.exp(ends) if log else ends
            for label in groups.labels:
                member = groups.members(rows, label)
                y = y_all[(u == level) & member & ~bad & np.isfinite(y_all)]
                if y.size:
                    line = groups.colour[label] if groups.by else "k"
                    ax.plot(ends, [np.median(y)] * 2, color=line, lw=1.5)
    for label in groups.labels:
        pick = groups.members(rows, label) & ~bad
        shown_as = label if groups.by else "ok"
        ax.scatter(
            xs[pick], y_all[pick], s=12, alpha=0.6, color=groups.colour[label], label=shown_as
        )
    if bad.any():
        ax.scatter(xs[bad], np.full(bad.sum(), top), marker="x", color="tab:red", label="failed")
    ax.set_xlabel(labelled(name))
    ax.legend(fontsize=8)


def _is_numeric(rows: Sequence[Mapping], name: str) -> bool:
    return all(_is_number(r.get(name)) for r in rows)

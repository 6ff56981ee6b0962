"""The identification's report beside its Markdown: the fit's figures, and the page as HTML.

``python -m tt_mujoco.identify`` writes ``identify.md`` (:func:`tt_mujoco.identify.main`); this
module draws what the fit shows (the logged hitch angles against the fitted train's, replayed
open loop; how the estimates correlate) as PNG files the Markdown links, and turns the same
Markdown into ``identify.html``, one file with its figures inside, which any browser opens.
The page is made from the Markdown, so both say the same; the Markdown the command writes uses
headings, paragraphs, tables, list items and images, which is all :func:`html_page` reads.
"""

from __future__ import annotations

import base64
import html
import math
import re

import numpy as np

__all__ = [
    "CORRELATION_PNG",
    "REPLAY_PNG",
    "SIMULATED_PNG",
    "figures",
    "html_page",
    "image_lines",
]

#: The figures' files in the output folder.
REPLAY_PNG = "identify_replay.png"
SIMULATED_PNG = "identify_simulated.png"
CORRELATION_PNG = "identify_correlation.png"
DPI = 110


def figures(fit, inertia) -> dict:
    """File name -> matplotlib figure of the report: the replay when the hitch angles were
    fitted (``fit``, an :class:`tt_mujoco.identify.Fit` or None), the correlations of each
    fit (``fit``, ``inertia``: an :class:`tt_mujoco.identify_inertia.InertiaFit` or None) of
    two parameters or more."""
    out = {}
    if fit is not None:
        out[REPLAY_PNG] = _replay_figure(fit.t, fit.logged, fit.replayed)
    if inertia is not None and inertia.simulated is not None:
        out[SIMULATED_PNG] = _simulated_figure(*inertia.simulated)
    fits = [f for f in (fit, inertia) if f is not None and len(f.names) >= 2]
    if fits:
        out[CORRELATION_PNG] = _correlation_figure(fits)
    return out


def _replay_figure(t, logged, replayed):
    from matplotlib.figure import Figure

    n = logged.shape[1]
    fig = Figure(figsize=(8, 2.4 * n + 1.0), layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for k, ax in enumerate(axes):
        name = "phi" if k == 0 else f"phi_{k + 1}"
        error = replayed[:, k] - logged[:, k]
        rms = math.degrees(float(np.sqrt(np.nanmean(error**2))))
        ax.plot(t, np.degrees(logged[:, k]), color="0.3", lw=1.0, label=f"{name} logged")
        ax.plot(
            t,
            np.degrees(replayed[:, k]),
            "--",
            color="tab:blue",
            lw=1.2,
            label=f"{name} of the fitted train, replayed (rms error {rms:.3g} deg)",
        )
        ax.set_ylabel(f"{name} (deg)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("Hitch angles: the log, and the fitted train under the logged v and omega")
    return fig


def _simulated_figure(t, logged, simulated):
    """The log's v and omega against the fitted train's, simulated from the wheel torques
    segment by segment (each from its own first velocity)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 5.8), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    units = ("v (m/s)", "omega (rad/s)")
    for channel, (ax, unit) in enumerate(zip(axes, units, strict=True)):
        for s in range(t.shape[0]):
            first = s == 0
            ax.plot(
                t[s], logged[s, :, channel], color="0.3", lw=1.0, label="logged" if first else None
            )
            ax.plot(
                t[s],
                simulated[s, :, channel],
                "--",
                color="tab:blue",
                lw=1.2,
                label="the fitted train, from the torques" if first else None,
            )
        ax.set_ylabel(unit)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("Speed and yaw rate: the log, and the fitted train under the logged torques")
    return fig


def _correlation_figure(fits):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4.2 * len(fits) + 0.6, 4.2), layout="constrained")
    axes = fig.subplots(1, len(fits), squeeze=False)[0]
    for ax, fit in zip(axes, fits, strict=True):
        names = list(fit.names)
        shown = ax.imshow(np.nan_to_num(fit.correlation), vmin=-1.0, vmax=1.0, cmap="RdBu_r")
        ax.set_xticks(range(len(names)), names, rotation=45, ha="right", fontsize=8)
        ax.set_yticks(range(len(names)), names, fontsize=8)
        for i in range(len(names)):
            for j in range(len(names)):
                value = fit.correlation[i, j]
                text = f"{value:+.2f}" if math.isfinite(value) else "n/a"
                color = "white" if math.isfinite(value) and abs(value) > 0.6 else "black"
                ax.text(j, i, text, ha="center", va="center", fontsize=7, color=color)
    fig.colorbar(shown, ax=list(axes), shrink=0.8, label="correlation of the estimates")
    fig.suptitle("Correlations of the estimates (beyond +-0.95: not told apart by this log)")
    return fig


def image_lines(names) -> str:
    """Markdown lines showing the figures ``names`` (files beside the page)."""
    return "".join(f"\n![{name}]({name})\n" for name in names)


_IMAGE = re.compile(r"!\[([^\]]*)\]\(([^)]+)\)")
_CODE = re.compile(r"`([^`]+)`")


def _inline(text: str) -> str:
    return _CODE.sub(r"<code>\1</code>", html.escape(text, quote=False))


def html_page(markdown: str, images: dict[str, bytes], title: str) -> str:
    """The Markdown the command writes as one HTML page, each image whose file ``images``
    holds (name -> PNG bytes) inside it.

    Parameters
    ----------
    markdown : str
        Headings (``#``, ``##``), paragraphs, tables (``|`` rows, the second one dashes), list
        items (``- ``) and images (``![alt](file)``).
    images : dict of str to bytes
    title : str

    Returns
    -------
    str
    """
    body, table, items, paragraph = [], [], [], []

    def close() -> None:
        if table:
            head, *rows = [
                [cell.strip() for cell in row.strip().strip("|").split("|")] for row in table
            ]
            rows = [r for r in rows if not all(set(c) <= set("-: ") for c in r)]
            body.append("<table><tr>" + "".join(f"<th>{_inline(c)}</th>" for c in head) + "</tr>")
            body.extend(
                "<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>" for r in rows
            )
            body.append("</table>")
        if items:
            body.append("<ul>" + "".join(f"<li>{_inline(i)}</li>" for i in items) + "</ul>")
        if paragraph:
            body.append(f"<p>{_inline(' '.join(paragraph))}</p>")
        table.clear(), items.clear(), paragraph.clear()

    for line in markdown.splitlines():
        image = _IMAGE.fullmatch(line.strip())
        if not line.strip():
            close()
        elif line.startswith("#"):
            close()
            level = min(len(line) - len(line.lstrip("#")), 3)
            body.append(f"<h{level}>{_inline(line.lstrip('#').strip())}</h{level}>")
        elif line.startswith("|"):
            if items or paragraph:
                close()
            table.append(line)
        elif line.startswith("- "):
            if table or paragraph:
                close()
            items.append(line[2:])
        elif image is not None:
            close()
            alt, name = image.groups()
            if name in images:
                data = base64.b64encode(images[name]).decode("ascii")
                source = f"data:image/png;base64,{data}"
                body.append(f'<p><img alt="{html.escape(alt)}" src="{source}"></p>')
        else:
            if table or items:
                close()
            paragraph.append(line.strip())
    close()
    style = (
        "body{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em}"
        "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:.2em .6em}"
        "img{max-width:100%}"
    )
    return (
        f'<!DOCTYPE html>\n<html lang="en">\n<head><meta charset="utf-8">'
        f"<title>{html.escape(title)}</title><style>{style}</style></head>\n<body>\n"
        + "\n".join(body)
        + "\n</body>\n</html>\n"
    )

"""A study's figures (`[[plot]]` in the study file, docs/studies.md): maps, histograms and
scatter plots of the rows, labelled with names and units."""

import textwrap

import numpy as np

from . import labels


def plot(spec, results, out, variables=None):
    """The study's `[[plot]]` figures: `map` (a metric over two parameters, one panel per value
    of a third), `histogram` of a metric, `scatter` of a metric against a parameter. Axes are
    labelled with each quantity's name and unit (`stewart_fmu.labels`; `variables`: the FMUs'
    variable tables). Yields (path, None) for each figure written, (path, reason) for one that
    could not be: rows are never lost to a plot."""
    if not len(results) or not spec.get("plot"):
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    for i, p in enumerate(spec["plot"]):
        path = out / p.get("file", f"plot{i + 1}.png")
        # The schema refuses names that leave --out; a symbolic link inside it could still.
        if out.resolve() not in path.resolve().parents:
            yield path, f"{path} is outside --out {out}"
            continue
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fig = _figure(plt, spec, results, p, variables)
            fig.savefig(path, dpi=110)
            plt.close(fig)
        except Exception as e:  # noqa: BLE001 - a figure that fails is reported; the rows are kept
            plt.close("all")
            yield path, f"{type(e).__name__}: {e}"
            continue
        yield path, None


def colour_limits(values):
    """Colour-scale limits that show the bulk of the values: the data's range, cut at 3
    interquartile ranges beyond the quartiles, so that one outlier (a run at rest, 1e-15 m)
    does not take the whole scale. Returns (lo, hi)."""
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    if not len(finite):
        return 0.0, 1.0
    q1, q3 = np.percentile(finite, [25, 75])
    spread = q3 - q1
    lo = max(finite.min(), q1 - 3 * spread) if spread > 0 else finite.min()
    hi = min(finite.max(), q3 + 3 * spread) if spread > 0 else finite.max()
    return (lo, hi) if hi > lo else (lo - 0.5, hi + 0.5)


class _Quantities:
    """The rows' columns (a run parameter or a metric) and their labels, for one figure."""

    def __init__(self, spec, results, variables):
        self.results, self.variables = results, variables
        self.nondimensional = spec["study"].get("units") == "nondimensional"

    def column(self, name):
        results = self.results
        return results[f"param:{name}"] if f"param:{name}" in results else results[name]

    def name(self, name):
        return labels.label(name, self.variables, self.nondimensional)

    def label(self, name, width=48):
        return textwrap.fill(self.name(name), width)


def _figure(plt, spec, results, p, variables=None):
    q = _Quantities(spec, results, variables)
    value = p.get("value", "max_leg_error")
    title = p.get("title", f"{spec['study']['name']}: {q.name(value)}")
    kind = p.get("kind", "histogram")
    if kind == "map":
        return _map(plt, q, p, value, title)
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    if kind == "scatter":
        ax.scatter(q.column(p["x"]), results[value], s=12)
        ax.set_xlabel(q.label(p["x"]))
        ax.set_ylabel(q.label(value))
        ax.grid(True, alpha=0.3)
    else:
        ax.hist(results[value].dropna(), bins=p.get("bins", 30))
        ax.set_xlabel(q.label(value))
        ax.set_ylabel("runs")
    ax.set_title(textwrap.fill(title, 64), fontsize=10)
    fig.tight_layout()
    return fig


def _map_grids(q, p, value, facets):
    """Per facet (a value of `p["facet"]`, or None): the x and y values and the grid of `value`
    (NaN for an unstable or failed run, unless `unstable_blank` is false), as shown (log10 with
    `log`)."""
    results, grids = q.results, []
    for facet in facets:
        part = results if facet is None else results[q.column(p["facet"]) == facet]
        xs, ys = sorted(q.column(p["x"])[part.index].unique()), sorted(q.column(p["y"])[part.index].unique())
        grid = np.full((len(ys), len(xs)), np.nan)
        for _, r in part.iterrows():
            x, y = r.get(f"param:{p['x']}", r.get(p["x"])), r.get(f"param:{p['y']}", r.get(p["y"]))
            v = r[value] if r["stable"] or not p.get("unstable_blank", True) else np.nan
            grid[ys.index(y), xs.index(x)] = v
        with np.errstate(divide="ignore", invalid="ignore"):
            shown = np.log10(grid) if p.get("log") else grid
        grids.append((xs, ys, grid, shown))
    return grids


def _map(plt, q, p, value, title):
    """A metric over two parameters, one panel per value of a third, on one colour scale robust
    to outliers; cells beyond it are marked."""
    facets = sorted(q.column(p["facet"]).unique()) if p.get("facet") else [None]
    fig, axes = plt.subplots(1, len(facets), figsize=(max(7.5, 4.2 * len(facets) + 1.5), 5.0), squeeze=False,
                             sharey=True, layout="constrained")
    grids = _map_grids(q, p, value, facets)
    every = np.concatenate([g[3].ravel() for g in grids])
    lo, hi = colour_limits(every)
    below, above = bool(np.any(every < lo)), bool(np.any(every > hi))
    for ax, facet, (xs, ys, grid, shown) in zip(axes[0], facets, grids):
        im = ax.imshow(shown, origin="lower", aspect="auto", cmap="viridis", vmin=lo, vmax=hi)
        ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs], rotation=45)
        ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys])
        if facet is not None:
            ax.set_title(labels.facet_title(p["facet"], facet, q.variables, q.nondimensional))
        for (yi, xi), v in np.ndenumerate(shown):
            if np.isnan(grid[yi, xi]):
                ax.text(xi, yi, "x", ha="center", va="center", color="red")
            elif v < lo or v > hi:
                ax.text(xi, yi, "<" if v < lo else ">", ha="center", va="center", color="white", fontweight="bold")
    extend = {(True, True): "both", (True, False): "min", (False, True): "max"}.get((below, above), "neither")
    fig.supxlabel(q.label(p["x"], 90), fontsize=9)
    axes[0][0].set_ylabel(q.label(p["y"], 40), fontsize=9)
    fig.colorbar(im, ax=list(axes[0]), extend=extend,
                 label=textwrap.fill(("log10 of " if p.get("log") else "") + q.name(value), 40))
    note = "x: unstable or failed" + ("; < >: beyond the colour scale" if below or above else "")
    fig.suptitle(textwrap.fill(f"{title} ({note})", int(10 * fig.get_figwidth())), fontsize=10)
    return fig

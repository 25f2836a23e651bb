"""Plots of a calibration: the data against the fitted model with its 95 % band, the
residuals, and for a Bayesian fit the posterior (histograms and pairwise scatter); axes in the
designer's units where perga knows them (:mod:`perga.studies.user_units`), else SI."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from perga.output.figures import new_figure, save
from perga.studies.user_units import axis_label, metric_label

if TYPE_CHECKING:
    from perga.studies.calibrate import Calibration, Data, Fit


def _abscissa(data: Data) -> tuple[str, np.ndarray]:
    """The first numeric condition column (its label and values in the plotted unit), or the
    row number."""
    for name in data.conditions[0] if data.conditions else ():
        try:
            values = np.array([float(row[name]) for row in data.conditions])
        except (TypeError, ValueError):
            continue
        label, factor = axis_label(name)
        return label, values * factor
    return "data row", np.arange(len(data.values), dtype=float)


def write_plots(calibration: Calibration, directory: Path) -> list[Path]:
    """fit.png (data and model per metric), residuals.png, posterior.png (Bayesian only)."""
    fit, data, simulated = calibration.fit, calibration.data, calibration.simulated
    name, x = _abscissa(data)
    order = np.argsort(x)
    band = np.array(fit.band)
    n = len(data.metrics)
    fig, axes = new_figure((5.0 * n, 4.0), 1, n, squeeze=False)
    for j, metric in enumerate(data.metrics):
        ax = axes[0, j]
        label, f = metric_label(metric)
        err = np.where(np.isfinite(data.sd[:, j]), data.sd[:, j], 0.0) * f
        ax.errorbar(x, data.values[:, j] * f, yerr=err, fmt="o", ms=4, label="measured")
        ax.fill_between(x[order], band[order, j, 0] * f, band[order, j, 1] * f, alpha=0.3,
                        label="model, 95 % band")  # fmt: skip
        ax.plot(x[order], simulated[order, j] * f, "-", label="model at the fit")
        ax.set_xlabel(name)
        ax.set_ylabel(label)
        ax.legend(fontsize=8)
    title = ", ".join(f"{k} = {v:.4g}" for k, v in zip(fit.keys, fit.values, strict=True))
    fig.suptitle(f"{fit.method}: {title}", fontsize=9)
    paths = [directory / "fit.png"]
    save(fig, paths[0])
    residuals = np.array(fit.residuals)
    fig, ax = new_figure((5.5, 4.0))
    for j, metric in enumerate(data.metrics):
        ax.plot(x, residuals[:, j], "o", label=metric)
    ax.axhline(0.0, color="0.5", lw=1)
    ax.set_xlabel(name)
    ax.set_ylabel("residual (simulated − measured)/sd")
    ax.legend(fontsize=8)
    paths.append(directory / "residuals.png")
    save(fig, paths[-1])
    if fit.samples:
        paths.append(_posterior(fit, directory / "posterior.png"))
    return paths


def _posterior(fit: Fit, path: Path) -> Path:
    samples = np.array(fit.samples)
    k = samples.shape[1]
    fig, axes = new_figure((3.0 * k, 3.0 * k), k, k, squeeze=False)
    labels, factors = zip(*(axis_label(key) for key in fit.keys), strict=True)
    samples = samples * np.array(factors)
    for i in range(k):
        for j in range(k):
            ax = axes[i, j]
            if i == j:
                ax.hist(samples[:, i], bins=30, color="C0")
                for bound in fit.intervals[i]:
                    ax.axvline(bound * factors[i], color="C1", lw=1)
            elif j < i:
                ax.plot(samples[:, j], samples[:, i], ".", ms=1, alpha=0.4)
            else:
                ax.axis("off")
            if i == k - 1:
                ax.set_xlabel(labels[j], fontsize=8)
            if j == 0 and i > 0:
                ax.set_ylabel(labels[i], fontsize=8)
    fig.suptitle(f"posterior ({len(samples)} samples); 95 % intervals in orange", fontsize=9)
    save(fig, path)
    return path

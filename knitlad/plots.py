"""Figures: the spatio-temporal diagram of a ladder (paper, Fig. 3b,d and Fig. 7)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np


def spatio_temporal_diagram(result, path: str | Path) -> Path:
    """Laddered cells of the laddering column against time, with the front and the v_lad fit."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    t_ms = np.array(result.times_s) * 1e3
    fig, ax = plt.subplots(figsize=(5, 3.5), dpi=120)
    if result.column_history:
        cells = np.array(result.column_history, dtype=float).T
        ax.imshow(cells, origin="lower", aspect="auto", cmap="Greys", vmin=0, vmax=1.5,
                  extent=(t_ms[0], t_ms[-1], -0.5, cells.shape[0] - 0.5) if t_ms.size > 1 else None)
    r0 = result.settings.n_y // 2
    ax.plot(t_ms, r0 + np.array(result.front_up), color="tab:red", lw=1.2, label="front (up)")
    ax.plot(t_ms, r0 - np.array(result.front_down), color="tab:blue", lw=1.2, label="front (down)")
    ax.axhline(r0, color="k", lw=0.5, ls=":")
    ax.set_xlabel("time since the cut [ms]")
    ax.set_ylabel("course (stitch) index")
    v = result.v_lad_over_cb
    title = f"f_x^ini = {result.fx_ini:.2f}, v_lad/c_b = {v:.3f}" if np.isfinite(v) else f"f_x^ini = {result.fx_ini:.2f}"
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    tmp = path.with_name(path.name + ".tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    os.replace(tmp, path)
    return path

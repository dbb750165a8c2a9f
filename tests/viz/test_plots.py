"""knitlad/viz/plots.py: the figures say how each run ended and how far to trust it."""


def test_the_sweep_plots_draw_each_runs_end_apart_and_the_papers_points_only_beside_its_knits(tmp_path, monkeypatch):
    """In a 2 x 2 sweep on 6 x 8 every job reached the knit's edge and nothing said so; fx_fin_vs_fx_ini was
    titled an arrest tension over runs that never arrested; velocity_vs_fx had no error bars and overlaid the
    paper's 42 x 42 DER points on 6 x 8 knits."""
    import pandas as pd

    from knitlad.viz import plots

    df = pd.DataFrame({"status": "ok", "scene": "ladder", "n_x": 6, "n_y": 8, "preset": "fast", "mu": [0.2, 0.6, 0.2],
                       "fx_ini": [4.0, 4.0, 12.0], "fx_fin": [1.0, 2.0, 3.0], "n_lad_over_ny": [0.5, 0.875, 0.875],
                       "v_lad_over_cb": [0.3, 0.2, 0.9], "v_fit_first": [2, 1, 2], "v_fit_last": [10, 2, 10],
                       "reached_edge": [False, True, True],
                       "stop_reason": ["no cell changed for 2.0 ms", "ladder reached an edge course",
                                       "ladder reached an edge course"]})
    assert list(plots.run_ends(df)) == ["arrested", "edge", "edge"]
    assert list(plots.run_ends(df, velocity=True)) == ["arrested", "short", "edge"]
    seen = {}

    def labelled(fig, ax, xlabel, ylabel, title, path):
        seen[path.stem] = (title, ax.get_legend_handles_labels()[1], len(ax.containers))
        return path

    monkeypatch.setattr(plots, "_labelled", labelled)
    plots.summary_plots(df, tmp_path)
    title, labels, bars = seen["velocity_vs_fx"]
    assert not any("DER" in label for label in labels) and bars >= 2 and "error" in title
    assert any("reached an edge" in label for label in labels) and any("rough" in label for label in labels)
    assert "at the stop" in seen["fx_fin_vs_fx_ini"][0]
    plots.summary_plots(df.assign(n_x=42, n_y=42), tmp_path)
    assert any("DER" in label for label in seen["velocity_vs_fx"][1])

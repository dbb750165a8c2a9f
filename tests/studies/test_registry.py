"""knitlad.studies.registry: each scene names its config, runner and summary columns once."""

from __future__ import annotations

import inspect

from knitlad.experiments.config import CutConfig
from knitlad.studies.registry import SCENES, stretch_of


def test_every_scene_has_a_runner_taking_the_progress_and_distinct_summary_columns():
    for name, scene in SCENES.items():
        assert list(inspect.signature(scene.run).parameters) == ["cfg", "output", "folder", "progress"], name
        assert len(set(scene.summary_keys)) == len(scene.summary_keys), name
        assert "job_wall_s" in scene.summary_keys and scene.description, name


def test_laddering_jobs_share_a_stretch_exactly_when_their_stretch_settings_agree():
    """A sweep over mu (the dynamics) stretches once; another tension or resolution is another knit."""
    base = CutConfig(n_x=6, n_y=8, fx=4.0, mu=0.4)
    assert stretch_of(base) == stretch_of(base.replace(mu=0.0, max_time_ms=3.0))
    assert stretch_of(base) != stretch_of(base.replace(fx=5.0))
    assert stretch_of(base) != stretch_of(base.replace(preset="fast"))

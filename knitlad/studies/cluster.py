"""Batch clusters for sweeps: a YAML file that says which dask-jobqueue cluster to start (``knitlad sweep
CONFIG --cluster FILE``).

The sweep's jobs then run as Dask tasks on workers that the batch system starts, one
worker per batch job, as with ``--executor dask --scheduler ADDRESS`` but without a
scheduler to start by hand. The output folder must be on a file system the workers share,
and the workers must run the same knitlad (the same environment, on a shared disk).

    kind: slurm          # slurm, pbs, sge, lsf, oar, htcondor, moab; local: workers as local processes
    jobs: 8              # batch jobs to submit, one Dask worker of one thread each
    options:             # handed to dask_jobqueue.<Kind>Cluster as they are
      queue: normal
      account: my-project
      cores: 1
      memory: 4GB
      walltime: "04:00:00"
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, ValidationInfo, field_validator

from knitlad.experiments.config import one_line
from knitlad.io.atomic import read_config_text
from knitlad.studies.sweep import SweepError, bounded_yaml

KINDS = {"slurm": "SLURMCluster", "pbs": "PBSCluster", "sge": "SGECluster", "lsf": "LSFCluster",
         "oar": "OARCluster", "htcondor": "HTCondorCluster", "moab": "MoabCluster"}


class ClusterConfig(BaseModel):
    """Which batch cluster to start for a sweep, and how many workers."""

    model_config = ConfigDict(extra="forbid")

    kind: Literal["slurm", "pbs", "sge", "lsf", "oar", "htcondor", "moab", "local"] = Field(description=(
        "the batch system (dask-jobqueue's cluster of that name); local: the same jobqueue cluster with its "
        "workers started as local processes, to try a config on a laptop [-]"))
    jobs: int = Field(ge=1, le=10_000, strict=True, description="batch jobs to submit, each one Dask worker [-]")
    options: dict[str, Any] = Field(default_factory=dict, description=(
        "keyword arguments of the dask-jobqueue cluster (queue, account, cores, memory, walltime, "
        "job_extra_directives, ...), as its documentation gives them [-]"))

    @field_validator("options")
    @classmethod
    def walltime_is_a_duration(cls, options: dict) -> dict:
        """A walltime is text, "HH:MM:SS" (the batch systems' form): a bare number was taken silently."""
        if "walltime" in options and not isinstance(options["walltime"], str):
            raise ValueError(f"walltime: a duration as text, \"HH:MM:SS\", got {options['walltime']!r}")
        return options

    @field_validator("options")
    @classmethod
    def a_local_workers_python_exists(cls, options: dict, info: ValidationInfo) -> dict:
        """A local cluster's workers run ``python`` on this machine: a path that is not an executable failed only
        once the workers started, with their tracebacks."""
        python = options.get("python")
        if info.data.get("kind") == "local" and python is not None:
            if not str(python).strip() or shutil.which(str(python).split()[0]) is None:
                raise ValueError(f"python: {python!r} is not an executable on this machine")
        return options

    def _classes(self):
        """(the dask-jobqueue cluster class, its job class)."""
        try:
            import dask_jobqueue
            from dask_jobqueue.local import LocalCluster
        except ImportError:
            raise SweepError("--cluster: needs dask-jobqueue (pip install 'knitlad[cluster]')") from None
        cls = LocalCluster if self.kind == "local" else getattr(dask_jobqueue, KINDS[self.kind])
        return cls, cls.job_cls

    def _options(self) -> dict:
        options = {"cores": 1, "processes": 1, "memory": "4GB", **self.options}
        # the dashboard on this machine's loopback unless the file asks otherwise: not open to the network
        options["scheduler_options"] = {"dashboard_address": "127.0.0.1:0", **options.get("scheduler_options", {})}
        return options

    def start(self):
        """The dask-jobqueue cluster, asked for ``jobs`` workers (a :class:`SweepError` if it cannot be made, or if
        the batch system's submit command is not on this machine)."""
        cls, job_cls = self._classes()
        submit = getattr(job_cls, "submit_command", None)
        if submit and shutil.which(submit.split()[0]) is None:
            raise SweepError(f"--cluster: a {self.kind} cluster submits its workers with {submit.split()[0]}, which is "
                             "not on this machine's PATH (run from the cluster's login node)")
        try:
            cluster = cls(**self._options())
        except Exception as e:  # noqa: BLE001 - a bad option: one line
            first = str(e).splitlines()[0] if str(e) else ""
            raise SweepError(f"--cluster: cannot start a {self.kind} cluster ({type(e).__name__}: {first})") from None
        cluster.scale(jobs=self.jobs)
        return cluster

    def job_script(self) -> str:
        """The batch script each worker is submitted with (to check a config before anything is submitted): made
        by the job class alone, so that nothing (no scheduler, no dashboard) is started."""
        _, job_cls = self._classes()
        options = {k: v for k, v in self._options().items() if k not in ("scheduler_options", "n_workers")}
        try:
            return job_cls(scheduler="tcp://SCHEDULER:8786", name="dask-worker", **options).job_script()
        except Exception as e:  # noqa: BLE001 - a bad option: one line
            first = str(e).splitlines()[0] if str(e) else ""
            raise SweepError(f"--cluster: not a {self.kind} worker's settings ({type(e).__name__}: {first})") from None


def load_cluster(path: str | Path) -> ClusterConfig:
    """Read and validate a cluster file; every problem is a :class:`SweepError` of one line."""
    path = Path(path)
    try:
        raw = bounded_yaml(read_config_text(path), str(path))
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise SweepError(f"--cluster {path}: cannot read ({getattr(e, 'strerror', None) or e})") from None
    except yaml.YAMLError as e:
        raise SweepError(f"--cluster {path}: not valid YAML ({getattr(e, 'problem', None) or e})") from None
    if not isinstance(raw, dict):
        raise SweepError(f"--cluster {path}: the file must be a mapping with keys kind, jobs, options")
    try:
        return ClusterConfig.model_validate(raw)
    except ValidationError as e:
        raise SweepError(f"--cluster {path}: {one_line(e)}") from None

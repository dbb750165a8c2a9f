"""The kernels' compiled cache (knitlad/engine/kernels/__init__.py): it holds only what the present kernel
sources compile to, so an edited kernel, or one it calls in another file, is compiled anew."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from knitlad.engine import kernels
from knitlad.engine.kernels.contact_law import LAWS, normal_spring, normal_spring_energy

PACKAGE = Path(kernels.__file__).resolve().parents[3]  # the folder holding knitlad/


def test_every_kernel_of_the_folder_is_cached_under_the_stamp_of_all_the_kernel_sources():
    from knitlad.engine.kernels.contact import contact_energy
    from knitlad.engine.kernels.integrate import verlet_steps

    for kernel in (verlet_steps, contact_energy, normal_spring):
        locator = kernel._cache._impl._locator
        assert isinstance(locator, kernels._FromKernelSources)
        assert locator.get_source_stamp() == kernels.SOURCES_STAMP == kernels.kernel_sources_stamp()


def test_the_stamp_changes_with_any_kernel_file(tmp_path):
    folder = tmp_path / "kernels"
    shutil.copytree(kernels.KERNELS_DIR, folder, ignore=shutil.ignore_patterns("__pycache__"))
    assert kernels.kernel_sources_stamp(folder) == kernels.SOURCES_STAMP
    law = folder / "contact_law.py"
    law.write_text(law.read_text() + "\n# an edit\n")
    assert kernels.kernel_sources_stamp(folder) != kernels.SOURCES_STAMP


def test_a_law_mode_without_a_branch_gives_nan_not_another_laws_force():
    unknown = max(mode for mode, _ in LAWS.values()) + 1
    assert np.isnan(normal_spring(unknown, 1e3, 1e-5, 1e-5))
    assert np.isnan(normal_spring_energy(unknown, 1e3, 1e-5, 1e-5))


ENERGY = """
import numpy as np, knitlad as kl
from knitlad.engine.contact import ContactModel, make_contacts
from knitlad.engine.kernels.contact import contact_energy, refresh_contacts
D = kl.NYLON.diameter
scene = kl.Scene()
for k in range(2):  # two straight yarns crossing at right angles, pressed 5 % of d into each other
    t = np.linspace(-3 * D, 3 * D, 7)
    x = np.zeros((7, 3)); x[:, k] = t; x[:, 2] = k * 0.95 * D
    scene.add_yarn(x)
rods = scene.build()
m, s = rods.model, rods.state
c = make_contacts(rods, ContactModel(stiffness=1e3))
refresh_contacts(s.x, m.edge_a, m.edge_b, m.edge_shift, c, s.v, 0.0)
n = c.n_pairs[0]
print(repr(contact_energy(s.x, m.edge_a, m.edge_b, m.edge_shift, c, c.pairs[:n], c.slip[:n])))
"""


@pytest.mark.process
def test_an_edited_law_is_seen_by_the_cached_kernel_that_calls_it_from_another_file(tmp_path):
    """A scratch copy of the package: the contact's energy (kernels/contact.py) is compiled and cached with
    the linear law; the law (kernels/contact_law.py) is then edited to a quarter of its energy, and a new process
    reads a quarter, with nobody deleting a cache."""
    shutil.copytree(PACKAGE / "knitlad", tmp_path / "knitlad", ignore=shutil.ignore_patterns("__pycache__"))

    def energy() -> float:
        p = subprocess.run([sys.executable, "-c", ENERGY], capture_output=True, text=True, cwd=tmp_path,
                           env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin", "NUMBA_NUM_THREADS": "1"})
        assert p.returncode == 0, p.stderr
        return float(p.stdout.strip().splitlines()[-1])

    before = energy()
    assert before > 0 and any((tmp_path / "knitlad/engine/kernels/__pycache__").glob("contact.contact_energy-*.nbi"))
    law = tmp_path / "knitlad/engine/kernels/contact_law.py"
    text = law.read_text()
    linear = "    if law == LINEAR:\n        return 0.5 * k * delta * delta\n"
    assert linear in text
    law.write_text(text.replace(linear, "    if law == LINEAR:\n        return 0.125 * k * delta * delta\n"))
    assert energy() == pytest.approx(0.25 * before, rel=1e-12)

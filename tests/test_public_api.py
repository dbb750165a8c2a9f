"""The public surface (``knitlad.__all__``) is recorded in docs/api_surface.txt: a name may not
disappear unless CHANGELOG.md says so, a new name is recorded, and the versions agree.

After a deliberate change: ``python -m tests.test_public_api --write``, then a CHANGELOG.md entry.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import sys
import tomllib
import warnings
from pathlib import Path

import pytest

import knitlad

ROOT = Path(__file__).resolve().parents[1]
RECORD = ROOT / "docs" / "api_surface.txt"
CHANGELOG = ROOT / "CHANGELOG.md"


def _parameters(obj) -> str:
    try:
        return "(" + ", ".join(p for p in inspect.signature(obj).parameters if p not in ("self", "cls")) + ")"
    except (TypeError, ValueError):
        return ""


def _members(cls) -> list[str]:
    """A class's public members: pydantic fields, dataclass fields, named-tuple fields, methods, properties."""
    names = set(getattr(cls, "model_fields", {}))
    if dataclasses.is_dataclass(cls):
        names |= {f.name for f in dataclasses.fields(cls)}
    names |= set(getattr(cls, "_fields", ()))
    for klass in cls.__mro__:
        if klass.__module__.startswith("knitlad"):
            names |= {n for n in vars(klass) if not n.startswith("_")}
    out = []
    for n in sorted(names):
        member = inspect.getattr_static(cls, n, None)
        if isinstance(member, (staticmethod, classmethod)):
            member = member.__func__
        out.append(f"{n}{_parameters(member)}" if inspect.isfunction(member) else n)
    return out


def public_surface() -> list[str]:
    """Every public name as a line: ``knitlad.Name``, ``knitlad.func(params)``, ``knitlad.Class.member``."""
    lines = []
    for name in sorted(knitlad.__all__):
        obj = getattr(knitlad, name)
        if inspect.isclass(obj):
            lines.append(f"knitlad.{name}{_parameters(obj) if not issubclass(obj, BaseException) else ''}")
            lines += [f"knitlad.{name}.{m}" for m in _members(obj)]
        elif inspect.isfunction(obj):
            lines.append(f"knitlad.{name}{_parameters(obj)}")
        else:
            lines.append(f"knitlad.{name}")
    return lines


def _recorded() -> list[str]:
    return [ln.strip() for ln in RECORD.read_text().splitlines() if ln.strip() and not ln.startswith("#")]


def _name(line: str) -> str:
    return line.split("(")[0]


def test_no_public_name_disappears_without_a_changelog_entry():
    now = {_name(ln) for ln in public_surface()}
    changelog = CHANGELOG.read_text()
    gone = [_name(ln) for ln in _recorded() if _name(ln) not in now
            and f"`{_name(ln).removeprefix('knitlad.')}`" not in changelog]
    assert not gone, f"public names gone without a CHANGELOG.md entry (`Name` under the new version): {gone}"


def test_every_public_name_and_signature_is_recorded():
    missing = sorted(set(public_surface()) - set(_recorded()))
    assert not missing, (f"public names or signatures not in {RECORD.name}: {missing}; record them with "
                         "`python -m tests.test_public_api --write` and say so in CHANGELOG.md")


def test_the_versions_agree():
    """The package, pyproject.toml, the newest CHANGELOG.md entry and CITATION.cff name one version."""
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    newest = re.search(r"^## (\d+\.\d+\.\d+) \(\d{4}-\d{2}-\d{2}\)", CHANGELOG.read_text(), re.M)
    assert newest, "CHANGELOG.md has no '## X.Y.Z (YYYY-MM-DD)' entry"
    cited = re.search(r"^version: (\S+)$", (ROOT / "CITATION.cff").read_text(), re.M)
    assert knitlad.__version__ == pyproject == newest.group(1) == cited.group(1)


def test_deprecated_names_still_work_and_warn():
    with pytest.warns(DeprecationWarning, match="dataclasses.replace"):
        m = knitlad.NYLON.with_(diameter=1e-4)
    assert m.diameter == 1e-4 and m.young_modulus == knitlad.NYLON.young_modulus
    stats = knitlad.ContactStats(3, 1e-6, 0.5, 1, 9)
    with pytest.warns(DeprecationWarning, match="contact_stats\\(\\).name"):
        assert stats["touching"] == 3 and stats["candidates"] == 9
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert stats[0] == 3 and stats.sliding == 1  # the named tuple's own access does not warn


def test_the_experiment_names_load_lazily_and_unknown_names_fail():
    assert knitlad.cut is __import__("knitlad.experiments.laddering", fromlist=["cut"]).cut
    with pytest.raises(AttributeError, match="no attribute 'cutt'"):
        knitlad.cutt  # noqa: B018


if __name__ == "__main__" and "--write" in sys.argv:
    RECORD.write_text("# knitlad's public surface (tests/test_public_api.py): names, and parameters of callables\n"
                      + "\n".join(public_surface()) + "\n")
    print(f"wrote {RECORD}")


def test_the_friction_coefficient_renamed_mu_keeps_its_old_name_with_a_warning():
    """0.5.0 named the Coulomb coefficient mu everywhere (config, contact, obstacles, simulation, kernel);
    the old name ``friction`` still works, for at least a version, and says so."""
    import warnings

    import knitlad as kl

    with pytest.warns(DeprecationWarning, match="mu="):
        model = kl.ContactModel(stiffness=1e3, friction=0.3)
    with pytest.warns(DeprecationWarning, match="mu="):
        plane = kl.Plane(stiffness=1.0, friction=0.2)
    assert model.mu == 0.3 and plane.mu == 0.2
    with pytest.warns(DeprecationWarning, match=r"\.mu"):
        assert model.friction == 0.3
    with pytest.raises(TypeError, match="both"), pytest.warns(DeprecationWarning):
        kl.Cylinder(stiffness=1.0, mu=0.1, friction=0.2)
    sim = kl.Simulation(_two_node_rods(), contact=model)
    with pytest.warns(DeprecationWarning, match=r"\.mu"):
        assert sim.friction == sim.mu == 0.3
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        kl.ContactModel(stiffness=1e3, mu=0.3)  # the new name: no warning


def _two_node_rods():
    import numpy as np

    import knitlad as kl

    scene = kl.Scene()
    scene.add_yarn(np.array([[0.0, 0.0, 0.0], [1e-3, 0.0, 0.0], [2e-3, 0.0, 0.0]]))
    return scene.build()


def _validators(cls) -> set[str]:
    """A pydantic config's validators: public by name, but pydantic's, not the user's to call."""
    decorators = getattr(cls, "__pydantic_decorators__", None)
    if decorators is None:
        return set()
    return set(decorators.model_validators) | set(decorators.field_validators)


def test_every_public_method_is_in_the_api_guide():
    """docs/api.md names each public function and method (a field or property may be named in a row)."""
    text = (ROOT / "docs" / "api.md").read_text()
    missing = []
    for line in public_surface():
        m = re.match(r"knitlad\.(\w+)(?:\.(\w+))?(\(.*\))?$", line)
        owner, member, parameters = m.groups()
        if member and (parameters is None or member in _validators(getattr(knitlad, owner))):
            continue
        if not re.search(rf"\b{re.escape(member or owner)}\b", text):
            missing.append(line)
    assert not missing, "not in docs/api.md: " + ", ".join(missing)


@pytest.mark.end_to_end
def test_the_api_guide_s_examples_run(capsys):
    """Each python block of docs/api.md runs as written, on its own."""
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "api.md").read_text(), flags=re.S)
    assert len(blocks) >= 4
    for k, block in enumerate(blocks):
        with warnings.catch_warnings():
            warnings.simplefilter("error", knitlad.MovingSupportWarning)
            exec(compile(block, f"docs/api.md, example {k + 1}", "exec"), {})
    assert "14.8 mN" in capsys.readouterr().out


def test_the_settings_renamed_as_their_config_names_them_keep_their_old_names_with_a_warning():
    """0.14.0 gave each setting of the stretch, the stitch, the loops, protocol B, the tensile test and the snag
    its config's name (``lx``, not ``lx_over_l0``; ``resolution``, not ``nodes_per_stitch``): a stretched knit's
    ``settings.fx_target`` and ``StitchConfig.cell_settings(lx_over_l0=)`` still work, and say so."""
    import knitlad as kl

    settings = kl.CutConfig(fx=4.0, n_x=6, n_y=6).stretch_settings()
    with pytest.warns(DeprecationWarning, match=r"use \.fx"):
        assert settings.fx_target == settings.fx == 4.0
    with pytest.warns(DeprecationWarning, match=r"use \.resolution"):
        assert settings.nodes_per_stitch == settings.resolution
    with pytest.warns(DeprecationWarning, match="use lx="):
        assert kl.StitchConfig().cell_settings(lx_over_l0=0.3).lx == 0.3

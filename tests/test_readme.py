"""The README's Python example runs as written; its pictures come from its own demo command."""

import json
import pathlib
import re

import pytest


@pytest.mark.end_to_end
def test_readme_python_example_runs(capsys):
    text = (pathlib.Path(__file__).parents[1] / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "the README has no python example"
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "tip [m]" in out and "energies [J]" in out
    assert len(blocks) == 2 and len([line for line in out.splitlines() if line.startswith(("0.0 ", "0.4 ", "0.8 "))]) == 3


def test_readme_pictures_come_from_its_demo_command():
    """The pictures showed another run (f_x^ini 16.95, 1.5 ms) than the demo makes (scripts/paper/readme_pictures.py)."""
    root = pathlib.Path(__file__).parents[1]
    text = (root / "README.md").read_text()
    record = json.loads((root / "docs" / "readme_pictures.json").read_text())
    assert record["command"] in text.split("```bash", 1)[1].split("```", 1)[0]  # the README's command 1
    assert f"![the demo, {record['render_at_ms']:.2f} ms after the cut](docs/render_front.png)" in text
    assert f"f_x^ini = {record['fx_ini']:.2f}](docs/spatio_temporal.png)" in text
    for name in ("render_front.png", "spatio_temporal.png"):
        assert (root / "docs" / name).stat().st_size > 10_000

"""The README's Python example runs as written."""

import pathlib
import re


def test_readme_python_example_runs(capsys):
    text = (pathlib.Path(__file__).parents[1] / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "the README has no python example"
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "tip [m]" in out and "energies [J]" in out
    assert len(blocks) == 2 and len([line for line in out.splitlines() if line.startswith(("0.0 ", "0.4 ", "0.8 "))]) == 3

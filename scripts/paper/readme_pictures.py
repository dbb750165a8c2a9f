"""Remake the README's two pictures from the README's own demo command.

    python scripts/paper/readme_pictures.py

Runs the demo (the README's first command, without its install part) into runs/readme_demo,
renders its front view at the last stored frame, copies that render to docs/render_front.png and
the run's cell diagram to docs/spatio_temporal.png, and records what made them in
docs/readme_pictures.json. tests/test_readme.py checks that the README's command, its captions and
that record agree, so the pictures cannot drift from the commands that the README shows.
"""

from __future__ import annotations

import json
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

import h5py

ROOT = Path(__file__).resolve().parents[2]
RECORD = ROOT / "docs" / "readme_pictures.json"


def readme_demo_command() -> list[str]:
    """The `knitlad cut ...` of the README's first command (the part after its install)."""
    for line in (ROOT / "README.md").read_text().splitlines():
        if "pip install -e . && knitlad cut" in line:
            return shlex.split(line.split("&& knitlad cut", 1)[1].strip())
    raise SystemExit("README.md has no demo command")


def main() -> None:
    args = readme_demo_command()
    out = ROOT / "runs" / "readme_demo"
    args[args.index("--out") + 1] = str(out)
    knitlad = [sys.executable, "-m", "knitlad"]
    subprocess.run([*knitlad, "cut", *args, "--overwrite"], check=True)
    with h5py.File(out / "ladder.h5") as f:
        last_ms = float(f["frames/time"][-1]) * 1e3
        fx_ini = float(f.attrs["fx_ini"])
    subprocess.run([*knitlad, "render", str(out), "--at-ms", f"{last_ms:.3f}", "--view", "front"], check=True)
    render = sorted((out / "render").glob("render_front_*.png"))[-1]
    shutil.copyfile(render, ROOT / "docs" / "render_front.png")
    shutil.copyfile(out / "spatio_temporal.png", ROOT / "docs" / "spatio_temporal.png")
    RECORD.write_text(json.dumps({
        "command": "knitlad cut " + shlex.join(readme_demo_command()), "render_at_ms": round(last_ms, 3),
        "fx_ini": round(fx_ini, 2), "date": time.strftime("%Y-%m-%d"),
    }, indent=1) + "\n")
    print(f"docs/render_front.png ({last_ms:.3f} ms after the cut) and docs/spatio_temporal.png; {RECORD.name}")


if __name__ == "__main__":
    main()

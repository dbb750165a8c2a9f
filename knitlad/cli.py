"""Command line: ``knitlad demo`` (later ``cut``, ``sweep``, ``stitch``, ``loop``, ``plot``).

Bad input gets one line on stderr naming the option and why, and exit code 2,
before anything runs.
"""

from __future__ import annotations

import sys
import time

import typer

app = typer.Typer(
    add_completion=False,
    pretty_exceptions_enable=False,
    no_args_is_help=True,
    help="knitlad: discrete elastic rods with frictional contact, for the laddering of knitted fabric.",
)


def fail(message: str) -> None:
    """One-line error, exit code 2, no traceback."""
    typer.echo(f"knitlad: error: {message}", err=True)
    raise typer.Exit(code=2)


@app.command()
def demo(
    nodes: int = typer.Option(41, help="Nodes along the cantilever (>= 6)."),
) -> None:
    """Rod demo: a clamped Nylon cantilever against beam theory (a few seconds)."""
    if nodes < 6:
        fail(f"--nodes must be >= 6, got {nodes}")
    from knitlad.demo import cantilever_demo

    t = time.perf_counter()
    typer.echo(f"Nylon cantilever, 20 mm, {nodes} nodes (first run compiles the kernels, ~30 s)")
    rows = cantilever_demo(n_nodes=nodes)
    typer.echo(f"{'check':45s} {'knitlad':>12s} {'theory':>12s} {'rel. error':>10s}")
    for r in rows:
        err = abs(r["knitlad"] / r["theory"] - 1) if r["theory"] == r["theory"] else float("nan")
        err_s = f"{err:10.2e}" if err == err else " " * 10
        theory_s = f"{r['theory']:12.5g}" if r["theory"] == r["theory"] else " " * 12
        typer.echo(f"{r['check']:45s} {r['knitlad']:12.5g} {theory_s} {err_s}  [{r['unit']}]")
    typer.echo(f"wall time {time.perf_counter() - t:.1f} s")


@app.command()
def scales() -> None:
    """Print the paper's material and scales (f0, c_b, ...) in SI units."""
    from knitlad.units import NYLON, Scales

    for key, value in Scales(NYLON).as_attributes().items():
        typer.echo(f"{key:20s} {value:.6g}")


def main() -> None:  # pragma: no cover - console entry point
    sys.exit(app())

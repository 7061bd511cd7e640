"""Regenerate the committed models: ``python -m pkm_pin.builders [--out DIR]``.

Writes ``DIR/urdf/*.urdf`` and ``DIR/mechanisms/*.toml`` for every mechanism of
:data:`pkm_pin.builders.MECHANISMS` and ``DIR/pinned/*.toml`` for those of
:data:`pkm_pin.builders.PINNED` (default geometry, metres), and the serial-chain
URDFs of :mod:`pkm_pin.builders.serial_chains`. ``DIR`` defaults to ``models/`` of the
repository.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from . import MECHANISMS, PINNED, serial_chains

#: ``models/`` beside the package, in a source checkout.
DEFAULT_OUT = Path(__file__).resolve().parents[2] / "models"


def generate(out: Path) -> list[Path]:
    """Write every model under ``out``; return the paths written."""
    written = []
    for build in (*MECHANISMS.values(), *PINNED.values()):
        written += build().write(out)
    written += serial_chains.write_serial_models(out)
    return written


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m pkm_pin.builders", description=__doc__)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help=f"models folder (default: {DEFAULT_OUT})")
    args = parser.parse_args(argv)
    for path in generate(args.out):
        print(path)


if __name__ == "__main__":
    main()

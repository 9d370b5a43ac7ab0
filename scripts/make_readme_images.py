"""Regenerate the README's robot pictures in docs/images with ``kinengine show``.

python scripts/make_readme_images.py
"""

from __future__ import annotations

from pathlib import Path

from kinengine.cli import main

IMAGES = Path(__file__).resolve().parents[1] / "docs" / "images"
SAMPLE_Q = "0.3,-0.4,0.5,0.8,0.6,0.4"
"""The ABB IRB 120 sample pose [rad]."""
COMMANDS = {
    "abb_irb120_home.png": ["abb_irb120"],
    "abb_irb120_sample.png": ["abb_irb120", "--q", SAMPLE_Q, "--frames", "tool0", "--ellipsoid", "tool0"],
    "planar_3dof.png": ["planar_3dof", "--q", "0.9,-1.6,0.8", "--ellipsoid", "ee", "--view", "10,-80"],
    "scara.png": ["scara", "--q", "0.4,0.8,-0.5,0.1", "--ellipsoid", "ee"],
}


def run() -> None:
    IMAGES.mkdir(parents=True, exist_ok=True)
    for name, args in COMMANDS.items():
        if main(["show", *args, "-o", str(IMAGES / name), "--dpi", "90"]) != 0:
            raise SystemExit(f"kinengine show failed for {name}")


if __name__ == "__main__":
    run()

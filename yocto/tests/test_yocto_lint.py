"""oelint-adv (PyPI), the OpenEmbedded style checker, on every recipe and bbappend of the layer
for scarthgap: no finding of any severity. The only rule suppressed for the whole layer is
oelint.vars.homepageping (it reaches the network); each other suppression is an inline
`# nooelint:` in the recipe, with its reason. --extra-layer rauc gives the checker meta-rauc's
variables (the bundle recipe's)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import layer_parse

OELINT = [sys.executable, "-m", "oelint_adv", "--release", "scarthgap", "--suppress", "oelint.vars.homepageping",
          "--extra-layer", "rauc", "--jobs", "1", "--quiet", "--relpaths"]


def lint(layer: Path) -> subprocess.CompletedProcess:
    files = sorted(str(p.relative_to(layer)) for p in [*layer.glob("recipes-*/*/*.bb"), *layer.glob("recipes-*/*/*.bbappend")])
    return subprocess.run(OELINT + files, cwd=layer, capture_output=True, text=True, timeout=300)


def findings(result: subprocess.CompletedProcess) -> list[str]:
    return [line for line in (result.stdout + result.stderr).splitlines() if ":" in line and "oelint." in line
            and not line.strip().startswith("oelint.")]


def test_every_recipe_is_clean():
    result = lint(layer_parse.LAYER)
    assert result.returncode == 0 and not findings(result), "\n".join(findings(result))


def test_a_recipe_off_the_style_guide_is_reported(tmp_path):
    layer = tmp_path / "meta-mocap"
    shutil.copytree(layer_parse.LAYER, layer)
    recipe = next(layer.glob("recipes-mocap/mocap-edge-libs/*.bb"))
    recipe.write_text(recipe.read_text().replace('DEPENDS += "libcamera', 'DEPENDS += " libcamera'))
    result = lint(layer)
    assert result.returncode != 0 and any("oelint.vars.inconspaces" in f for f in findings(result))

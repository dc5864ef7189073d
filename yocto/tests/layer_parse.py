"""meta-mocap parsed by BitBake's own parser (the `bb` package of PyPI's bitbake-setup), over the
part of openembedded-core's configuration in oe_stub/: the configuration as the cooker reads it
(bitbake.conf, the layer's layer.conf, the distribution), then each recipe with its bbappends,
each in its own copy of the configuration."""

from __future__ import annotations

import functools
import logging
import re
import subprocess
import sys
from pathlib import Path

STUB = Path(__file__).with_name("oe_stub")
sys.path.insert(0, str(STUB / "python"))  # hashserv, which bb.siggen imports (oe_stub/python/hashserv)

import bb.data  # noqa: E402
import bb.parse  # noqa: E402
import bb.parse.parse_py.BBHandler as BBHandler  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
LAYER = REPO / "yocto" / "meta-mocap"
DISTRO = "mocap"

logging.getLogger("BitBake").setLevel(logging.WARNING)


def recipes() -> list[Path]:
    return sorted(LAYER.glob("recipes-*/*/*.bb"))


def appends() -> list[Path]:
    return sorted(LAYER.glob("recipes-*/*/*.bbappend"))


def configuration(tmpdir: Path, layer: Path = LAYER) -> bb.data_smart.DataSmart:
    """The configuration datastore: bitbake.conf, the layer (LAYERDIR while its layer.conf is
    read, as the cooker sets it), the mocap distribution, the base class."""
    d = bb.data.init()
    d.setVar("BBPATH", str(STUB))
    d.setVar("TMPDIR", str(tmpdir))
    bb.parse.handle(str(STUB / "conf" / "bitbake.conf"), d)
    d.setVar("LAYERDIR", str(layer))
    d.setVar("LAYERDIR_RE", re.escape(str(layer)))
    bb.parse.handle(str(layer / "conf" / "layer.conf"), d)
    d.expandVarref("LAYERDIR")
    d.expandVarref("LAYERDIR_RE")
    d.setVar("DISTRO", DISTRO)
    bb.parse.handle(f"conf/distro/{DISTRO}.conf", d, 1)
    d.setVar("__bbclasstype", "global")  # classes-global/, then classes-recipe/ for recipes
    BBHandler.inherit("base", "configuration INHERITs", 0, d)
    d.setVar("__bbclasstype", "recipe")
    bb.parse.init_parser(d)  # the signature generator finalising each recipe, as the cooker sets it
    return d


def parse(recipe: Path, config: bb.data_smart.DataSmart) -> bb.data_smart.DataSmart:
    """A recipe's datastore (its base variant), bbappends of the same name applied."""
    d = bb.data.createCopy(config)
    pn = recipe.stem.split("_")[0]
    matching = [a for a in appends() if a.stem.split("_")[0] == pn]
    d.setVar("__BBAPPEND", " ".join(map(str, matching)))
    return bb.parse.handle(str(recipe), d)[""]


@functools.cache
def parsed_layer(tmpdir: Path) -> dict[str, bb.data_smart.DataSmart]:
    """PN -> datastore of every recipe of the layer."""
    config = configuration(tmpdir)
    stores = {}
    for recipe in recipes():
        d = parse(recipe, config)
        stores[d.getVar("PN")] = d
    return stores


def words(d: bb.data_smart.DataSmart, var: str) -> list[str]:
    """A list variable's words, version constraints (`pkg (>= 1)`) removed."""
    return list(bb.utils.explode_dep_versions2(d.getVar(var) or ""))


def run_task(d: bb.data_smart.DataSmart, task: str, env: dict[str, str]) -> subprocess.CompletedProcess:
    """A shell task of a parsed recipe run as BitBake writes it (the function and the functions
    it calls, with the exported variables), under bash -e."""
    script = Path(d.getVar("WORKDIR")) / f"run.{task}.sh"
    script.parent.mkdir(parents=True, exist_ok=True)
    with open(script, "w") as f:
        f.write("set -e\n")
        bb.data.emit_func(task, f, d)
        f.write(f"\n{task}\n")
    return subprocess.run(["bash", str(script)], capture_output=True, text=True, env=env, timeout=60)

"""meta-mocap's recipes as BitBake parses them (layer_parse): what each says is checked against
the code it builds, the files it installs and the layers the kas file pins."""

from __future__ import annotations

import fnmatch
import hashlib
import json
import os
import re
import shutil
import tomllib
from pathlib import Path

import pytest

import edge_imports
import layer_parse

REPO = layer_parse.REPO
UPSTREAM = tomllib.loads(Path(__file__).with_name("upstream.toml").read_text())
MOCAP_RECIPES = ["python3-mocap-edge", "mocap-edge-libs", "mocap-box-services"]


@pytest.fixture(scope="module")
def layer(tmp_path_factory) -> dict:
    return layer_parse.parsed_layer(tmp_path_factory.mktemp("oe"))


def packages(d) -> list[str]:
    return (d.getVar("PACKAGES") or "").split() or [d.getVar("PN")]


def test_every_recipe_and_append_parses(layer):
    assert sorted(layer) == sorted(
        "mocap-box-services mocap-edge-bundle mocap-edge-image mocap-edge-libs mocap-models-blazepose "
        "python3-mocap-edge python3-onnxruntime".split())
    assert not any(d.getVar("__SKIPPED") for d in layer.values())


def test_the_layer_and_distribution_settings(tmp_path):
    d = layer_parse.configuration(tmp_path)
    assert d.getVar("LAYERSERIES_COMPAT_mocap").split() == ["scarthgap"]
    assert d.getVar("BBFILE_COLLECTIONS").split() == ["mocap"]
    assert d.getVar("INIT_MANAGER") == "systemd"
    assert "rauc" in d.getVar("DISTRO_FEATURES").split()
    assert Path(d.getVar("MOCAP_LAYERDIR")).resolve() == layer_parse.LAYER


def test_the_projects_recipes_build_this_checkout_at_its_version(layer):
    version = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["version"]
    for pn in MOCAP_RECIPES:
        assert layer[pn].getVar("PV") == version, pn
        assert Path(layer[pn].getVar("S")).resolve() == REPO, pn
    models = (REPO / "edge" / "models" / "blazepose" / "README.md").read_text()
    assert f"MediaPipe {layer['mocap-models-blazepose'].getVar('PV')}" in models.splitlines()[0]


@pytest.mark.parametrize("pn", ["python3-mocap-edge", "mocap-edge-libs", "mocap-box-services", "mocap-models-blazepose"])
def test_licence_files_have_their_checksums(layer, pn):
    d = layer[pn]
    for entry in d.getVar("LIC_FILES_CHKSUM").split():
        path, *params = entry.removeprefix("file://").split(";")
        md5 = dict(p.split("=") for p in params)["md5"]
        assert hashlib.md5((Path(d.getVar("S")) / path).read_bytes()).hexdigest() == md5, entry


def test_sources_are_local_files_or_checksummed_downloads(layer):
    for pn, d in layer.items():
        for uri in (d.getVar("SRC_URI") or "").split():
            if uri.startswith("file://"):
                name = uri.removeprefix("file://").split(";")[0]
                assert any((Path(p) / name).exists() for p in d.getVar("FILESPATH").split(":")), (pn, uri)
            else:
                assert uri.startswith("https://") and re.fullmatch(r"[0-9a-f]{64}", d.getVarFlag("SRC_URI", "sha256sum")), (pn, uri)


def test_onnx_runtime_is_the_version_the_tests_run(layer):
    pinned = re.search(r"^onnxruntime==(\S+)$", (REPO / "requirements.txt").read_text(), re.M)[1]
    d = layer["python3-onnxruntime"]
    assert d.getVar("PV") == pinned and f"onnxruntime-{pinned}-" in d.getVar("SRC_URI")


def test_the_edge_packages_runtime_dependencies_are_what_its_code_imports(layer):
    rdepends = set(layer_parse.words(layer["python3-mocap-edge"], "RDEPENDS:python3-mocap-edge"))
    missing = needed_packages(edge_imports.edge_imports()) - rdepends
    assert not missing, f"python3-mocap-edge's RDEPENDS lacks {sorted(missing)}, which the edge's code imports"


def needed_packages(imports: dict[str, bool]) -> set[str]:
    """OpenEmbedded packages of the required imports (an import no distribution here provides,
    and no [optional_imports] entry excuses, fails)."""
    needed = set()
    for module, required in imports.items():
        if module in UPSTREAM["optional_imports"] or not required:
            continue
        dist = edge_imports.distribution(module)
        assert dist, f"the edge imports {module}, which no installed distribution provides: add it to requirements.txt"
        needed.add(edge_imports.package_name(dist, UPSTREAM["python_packages"]))
    return needed


def test_a_new_import_without_its_package_is_found():
    imports = dict(edge_imports.edge_imports(), serial=True)  # pyserial, as if the hub imported it itself
    assert "python3-pyserial" in needed_packages(imports)
    assert "python3-picamera2" not in needed_packages(imports)


def test_every_dependency_is_provided_by_this_layer_or_a_pinned_one(layer):
    ours = {p for pn, d in layer.items() for p in [pn, *packages(d)]}
    for pn, d in layer.items():
        names = layer_parse.words(d, "DEPENDS") + layer_parse.words(d, "IMAGE_INSTALL")
        names += [n for p in packages(d) for n in layer_parse.words(d, f"RDEPENDS:{p}")]
        unknown = {n for n in names if n not in ours and n not in UPSTREAM["packages"]}
        assert not unknown, f"{pn} depends on {sorted(unknown)}: no recipe here or in tests' upstream.toml"


def installed(layer, pn: str, tmp_path: Path) -> tuple[object, Path]:
    """A recipe's do_install run into tmp_path/image (S the checkout), as BitBake would."""
    d = layer_parse.bb.data.createCopy(layer[pn])
    d.setVar("D", str(tmp_path / "image"))
    d.setVar("WORKDIR", str(tmp_path))
    result = layer_parse.run_task(d, "do_install", {"PATH": os.environ["PATH"]})
    assert result.returncode == 0, result.stderr
    return d, tmp_path / "image"


def shipped_by(d, image: Path) -> dict[str, list[str]]:
    """Installed file (relative to D) -> the packages whose FILES match it."""
    out = {}
    for path in (p for p in image.rglob("*") if p.is_file() or p.is_symlink()):
        rel = "/" + str(path.relative_to(image))
        out[rel] = [pkg for pkg in packages(d) for pattern in (d.getVar(f"FILES:{pkg}") or "").split()
                    if fnmatch.fnmatch(rel, pattern) or rel.startswith(pattern.rstrip("/") + "/")]
    return out


def test_services_are_installed_and_each_file_shipped_once(layer, tmp_path):
    d, image = installed(layer, "mocap-box-services", tmp_path)
    files = shipped_by(d, image)
    assert files and all(len(pkgs) == 1 for pkgs in files.values()), files
    unit_dir = d.getVar("systemd_system_unitdir")
    for pkg in d.getVar("SYSTEMD_PACKAGES").split():
        for unit in d.getVar(f"SYSTEMD_SERVICE:{pkg}").split():
            assert files.get(f"{unit_dir}/{unit}") == [pkg], (pkg, unit)
    assert os.access(image / d.getVar("bindir").lstrip("/") / "mocap-wait-clock", os.X_OK)
    second = image / d.getVar("sysconfdir").lstrip("/") / "systemd/system/multi-user.target.wants/mocap-camera@1.service"
    assert os.readlink(second) == f"{unit_dir}/mocap-camera@.service"
    systemd_files = {p.name for p in (REPO / "edge" / "systemd").rglob("*") if p.is_file()}
    assert {Path(f).name for f in files} | {"mocap-edge.tmpfiles"} >= systemd_files


def test_the_models_are_installed_where_the_edge_looks(layer, tmp_path):
    d, image = installed(layer, "mocap-models-blazepose", tmp_path)
    models = image / d.getVar("datadir").lstrip("/") / "mocap-edge" / "models" / "blazepose"
    assert sorted(p.name for p in models.iterdir()) == ["LICENSE", "pose_detection.onnx", "pose_landmark_full.onnx"]
    assert all(len(pkgs) == 1 for pkgs in shipped_by(d, image).values())


def test_the_image_gives_root_the_builders_ssh_keys_or_none(layer, tmp_path):
    d = layer_parse.bb.data.createCopy(layer["mocap-edge-image"])
    d.setVar("WORKDIR", str(tmp_path))
    keys = tmp_path / "keys.pub"
    keys.write_text("ssh-ed25519 AAAAC3NzaC1lZDI1NTE5AAAAIA test@studio\n")
    authorized = Path(d.getVar("IMAGE_ROOTFS")) / d.getVar("ROOT_HOME").lstrip("/") / ".ssh" / "authorized_keys"
    assert "mocap_authorized_keys" in d.getVar("ROOTFS_POSTPROCESS_COMMAND")
    assert layer_parse.run_task(d, "mocap_authorized_keys", {"PATH": os.environ["PATH"]}).returncode == 0
    assert not authorized.exists()
    d.setVar("MOCAP_SSH_AUTHORIZED_KEYS", str(keys))
    assert layer_parse.run_task(d, "mocap_authorized_keys", {"PATH": os.environ["PATH"]}).returncode == 0
    assert authorized.read_text() == keys.read_text() and authorized.stat().st_mode & 0o777 == 0o600


def test_a_syntax_error_fails_the_parse(tmp_path):
    broken = tmp_path / "meta-mocap"
    shutil.copytree(layer_parse.LAYER, broken)
    recipe = next(broken.glob("recipes-mocap/python3-mocap-edge/*.bb"))
    recipe.write_text(recipe.read_text().replace("do_configure:prepend() {", "do_configure:prepend() {\n    (", 1)
                      .replace('RDEPENDS:${PN} += "', 'RDEPENDS:${PN} += "unclosed', 1).rstrip().rstrip('"'))
    with pytest.raises(Exception, match="(?i)unparsed|never closed|parse"):
        layer_parse.parse(recipe, layer_parse.configuration(tmp_path, broken))


def test_the_kas_file_pins_every_layer_the_layer_needs():
    kas = kas_config()
    listed = {}
    for name, repo in kas["repos"].items():
        if "url" in repo:
            assert re.fullmatch(r"[0-9a-f]{40}", repo.get("commit", "")), f"{name} is not pinned by commit"
            assert repo["branch"] == "scarthgap", name
        for path in (repo.get("layers") or {"": None}):
            key = f"{name}/{path}".rstrip("/")
            listed[key] = UPSTREAM["collections"].get(key)
    assert set(UPSTREAM["collections"]) <= set(listed)
    config = layer_parse.configuration(Path(os.environ.get("TMPDIR", "/tmp")))
    needed = set(d for d in (config.getVar("LAYERDEPENDS_mocap") or "").split() if not d.startswith("("))
    assert needed <= set(listed.values()), f"LAYERDEPENDS_mocap names {sorted(needed - set(listed.values()))}"
    assert kas["distro"] == layer_parse.DISTRO
    assert set(kas["target"]) == {"mocap-edge-image", "mocap-edge-bundle"}


def kas_config() -> dict:
    """yocto/kas/mocap-edge.yml, validated against kas's own schema."""
    import jsonschema
    import kas
    import yaml
    schema = json.loads(Path(kas.__file__).with_name("schema-kas.json").read_text())
    configs = {f.name: yaml.safe_load(f.read_text()) for f in (REPO / "yocto" / "kas").glob("*.yml")}
    for config in configs.values():
        jsonschema.validate(config, schema)
    return configs["mocap-edge.yml"]

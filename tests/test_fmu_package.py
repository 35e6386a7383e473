"""What a user gets in the FMU file: self-documentation, readable entries, stable names.

- documentation/index.html lists every variable of the FMU with its unit (read from the
  model description, which the build writes from the same declarations), the licences
  and model.png are there, and a scene with a figure shows it;
- every zip entry is readable by everyone (0644 files, 0755 folders): an extracted copy
  can be shared between users;
- modelIdentifier and modelName are the scene's name (the binaries are named after it),
  the GUID follows the content key, and <out>/<name>.fmu is the latest build: a second
  build of other content replaces it, the content-keyed files stay for the processes
  that use them; two FMUs of one name and different content run in one process.
"""

from __future__ import annotations

import html.parser
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import fmpy
import pytest

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import OK, Instance
from fmu_build import native_fmu

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
CONFIGS = {
    "fig13": load(ROOT / "scenarios" / "fig13.toml").config,
    "sweep": load(ROOT / "scenarios" / "sweep.toml").config,
    "full_rigid_body": ModelConfig.full("rigid_body"),
}


@pytest.fixture(scope="module", params=["pythonfmu", "native"])
def built(request) -> dict[str, fmu_build.Built]:
    """The FMUs of both targets: pythonfmu's and the native C FMU (fmu_build.native_fmu)."""
    if request.param == "native":
        from fmu_build import native_fmu

        return {name: native_fmu.build(cfg, OUT) for name, cfg in CONFIGS.items()}
    return {name: fmu_build.build(cfg, OUT) for name, cfg in CONFIGS.items()}


class _Table(html.parser.HTMLParser):
    """The rows of the HTML tables, as lists of cell texts."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[list[str]] = []
        self.images: list[str] = []
        self.links: list[str] = []
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "img":
            self.images.append(dict(attrs)["src"])
        elif tag == "a":
            self.links.append(dict(attrs)["href"])

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.rows[-1].append("".join(self._cell))
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def test_fmu_documents_itself(built):
    for name, b in built.items():
        with zipfile.ZipFile(b.stable) as z:
            names = set(z.namelist())
            page = z.read("documentation/index.html").decode()
            icon = z.read("model.png")
            licence = z.read("documentation/licenses/LICENSE.txt").decode()
        assert icon[:8] == b"\x89PNG\r\n\x1a\n", name
        assert "MIT License" in licence and "contact_fmu contributors" in licence
        native = isinstance(b, native_fmu.NativeBuilt)  # no pythonfmu inside
        assert ("documentation/licenses/pythonfmu-LICENSE.txt" in names) != native
        parsed = _Table()
        parsed.feed(page)
        header, *rows = parsed.rows
        md = fmpy.read_model_description(str(b.stable), validate=False)
        # every variable of the FMU, in value-reference order, with its unit and causality
        assert [r[0] for r in rows] == [v.name for v in md.modelVariables], name
        col = {h: i for i, h in enumerate(header)}
        for row, v in zip(rows, md.modelVariables, strict=True):
            assert row[col["unit"]] == (v.unit or ""), (name, v.name)
            assert row[col["causality"]] == v.causality, (name, v.name)
            assert row[col["variability"]] == v.variability, (name, v.name)
            assert row[col["description"]] == v.description, (name, v.name)
        for link in parsed.links + parsed.images:  # relative links resolve inside the FMU
            assert f"documentation/{link}" in names, (name, link)
    with zipfile.ZipFile(built["fig13"].stable) as z:  # a scene with a figure shows it
        assert "documentation/scene_fig13.png" in z.namelist()
    assert "scene_fig13.png" in _images(built["fig13"])
    assert _images(built["sweep"]) == []  # no docs/figures/scene_sweep.png


def _images(b: fmu_build.Built) -> list[str]:
    parsed = _Table()
    with zipfile.ZipFile(b.stable) as z:
        parsed.feed(z.read("documentation/index.html").decode())
    return parsed.images


def test_zip_entries_are_readable_by_everyone(built):
    for name, b in built.items():
        with zipfile.ZipFile(b.stable) as z:
            infos = z.infolist()
        folders = {i.filename for i in infos if i.is_dir()}
        for info in infos:
            mode = info.external_attr >> 16
            assert info.create_system == 3, (name, info.filename)  # Unix: modes apply
            if info.is_dir():
                assert mode == stat.S_IFDIR | 0o755, (name, info.filename, oct(mode))
            else:
                assert mode == stat.S_IFREG | 0o644, (name, info.filename, oct(mode))
                # every folder of a file has its own entry (0755), the root aside
                parts = info.filename.split("/")[:-1]
                for i in range(1, len(parts) + 1):
                    assert "/".join(parts[:i]) + "/" in folders, (name, info.filename)


def test_stable_identifier_and_binaries_named_after_it(built):
    for name, b in built.items():
        md = fmpy.read_model_description(str(b.stable))
        assert md.modelName == md.coSimulation.modelIdentifier == b.identifier
        assert b.stable.name == f"{b.identifier}.fmu"
        with zipfile.ZipFile(b.stable) as z:
            binaries = sorted(n for n in z.namelist() if n.startswith("binaries/") and "." in n)
        if isinstance(b, native_fmu.NativeBuilt):
            assert b.identifier == f"{name}_native" and md.guid == b.guid
            assert binaries == [f"binaries/linux64/{name}_native.so"]
            continue
        assert b.identifier == CONFIGS[name].name and md.guid == fmu_build.guid(b.key)
        assert binaries == [f"binaries/linux64/{name}.so", f"binaries/win64/{name}.dll"]
        # the per-content module inside the resources keeps FMUs apart in one process
        assert b.class_name != name and b.key[:12] in b.class_name


def test_rebuild_of_other_content_replaces_the_stable_file(tmp_path):
    """Same name, two contents (mu = 0.3, 0.25): two cached files, one <name>.fmu (the
    latest) that `fmpy validate` passes; the GUIDs differ, the identifiers do not; both
    FMUs run side by side in one process, each with its own friction bound mu P."""
    cfg = CONFIGS["sweep"]
    first = fmu_build.build(cfg, tmp_path)
    changed = ModelConfig.from_dict({**cfg.to_dict(), "starts": {**cfg.starts, "mu": 0.25}})
    second = fmu_build.build(changed, tmp_path)
    assert first.stable == second.stable == tmp_path / "sweep.fmu"
    assert second.stable.read_bytes() == second.path.read_bytes()
    assert first.path.is_file() and first.path != second.path
    assert sorted(p.name for p in tmp_path.glob("*.fmu")) == ["sweep.fmu"]
    g1 = fmpy.read_model_description(str(first.path)).guid
    g2 = fmpy.read_model_description(str(second.stable)).guid
    assert g1 != g2 and g1 == fmu_build.guid(first.key)
    proc = subprocess.run(
        [sys.executable, "-m", "fmpy", "validate", str(second.stable)],
        capture_output=True, text=True,
    )  # fmt: skip
    assert proc.returncode == 0 and "No problems found" in proc.stdout, proc.stdout
    # a cached build republishes its content: the stable file follows the latest call
    again = fmu_build.build(cfg, tmp_path)
    assert again.cached and again.stable.read_bytes() == first.path.read_bytes()
    # gross sliding (Omega_y = 0): |Tx| = mu P of each FMU's own mu
    locked = {"P": ex.P, "Vx": ex.speed_unit(), "Omega_y": 0.0}
    with Instance(first.path, "a", locked) as a, Instance(second.path, "b", locked) as b:
        assert a.step(1e-3) == OK and b.step(1e-3) == OK
        assert abs(a.get("Tx")) == pytest.approx(0.3 * ex.P, rel=1e-12)
        assert abs(b.get("Tx")) == pytest.approx(0.25 * ex.P, rel=1e-12)


def test_build_command_prints_the_stable_path(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "fmu_build", str(ROOT / "scenarios" / "sweep.toml"),
         "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split()[0] == str(tmp_path / "sweep.fmu")

"""Safe reading of untrusted URDF files (plm_pin/description/urdf.py)."""

from __future__ import annotations

import base64
import shutil
from pathlib import Path

import pytest

import plm_pin
from plm_pin import DescriptionError
from plm_pin.description import urdf as urdf_module
from plm_pin.description.urdf import read_urdf, read_urdf_text
from plm_pin.warnings import MissingMeshWarning

ROD_STL = (
    Path(__file__).resolve().parents[2].parent / "shared/interop/example-parallel-robots/5bar_linkage/rod.stl"
)

DOCTYPE_MESSAGE = "DOCTYPE and ENTITY declarations are not allowed in a URDF"

BILLION_LAUGHS = (
    '<?xml version="1.0"?>\n<!DOCTYPE robot [\n  <!ENTITY lol0 "lol">\n'
    + "".join(f'  <!ENTITY lol{i} "{f"&lol{i - 1};" * 10}">\n' for i in range(1, 10))
    + ']>\n<robot name="&lol9;"><link name="base"/></robot>\n'
)

XXE = (
    '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY xxe SYSTEM "file:///etc/passwd">]>\n'
    '<robot name="r"><link name="base"><visual><geometry><mesh filename="&xxe;"/></geometry>'
    "</visual></link></robot>\n"
)

SMALL_LAUGHS_BODY = (
    '<!DOCTYPE robot [<!ENTITY a "aaaa"><!ENTITY b "&a;&a;&a;">]>\n'
    '<robot name="&b;"><link name="base"/></robot>'
)


def _mesh_urdf(*filenames: str) -> str:
    """A two-link URDF whose first link has a box visual and whose second has the given meshes."""
    visuals = "".join(f'<visual><geometry><mesh filename="{f}"/></geometry></visual>' for f in filenames)
    return (
        '<robot name="meshy">'
        '<link name="base"><visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>'
        f'<link name="arm">{visuals}</link>'
        '<joint name="j" type="revolute"><parent link="base"/><child link="arm"/>'
        '<axis xyz="0 0 1"/><limit effort="1" velocity="1" lower="-3" upper="3"/></joint>'
        "</robot>"
    )


def _write(folder: Path, text: str | bytes, name: str = "robot.urdf") -> Path:
    path = folder / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    return path


def test_billion_laughs_is_refused_before_any_parsing(tmp_path, monkeypatch):
    """Nested ENTITY declarations are refused by the pre-check: no XML parser is ever built."""

    def no_parser():
        raise AssertionError("an XML parser was built for a DOCTYPE document")

    monkeypatch.setattr(urdf_module, "_parser", no_parser)
    path = _write(tmp_path, BILLION_LAUGHS)
    with pytest.raises(DescriptionError) as info:
        read_urdf(path)
    assert str(info.value).startswith(f"{path}: {DOCTYPE_MESSAGE}")
    assert "entity expansion and external entities are refused" in str(info.value)


def test_billion_laughs_is_refused_by_load(tmp_path):
    """plm_pin.load refuses a billion-laughs URDF with the DOCTYPE/ENTITY message."""
    _write(tmp_path, BILLION_LAUGHS)
    (tmp_path / "robot.plm.yaml").write_text("format: plm-pin/1\n")
    with pytest.raises(DescriptionError, match="DOCTYPE and ENTITY declarations are not allowed"):
        plm_pin.load(tmp_path / "robot.urdf")


def test_external_entity_is_refused(tmp_path):
    """An external entity (XXE on /etc/passwd) is refused, never resolved."""
    path = _write(tmp_path, XXE)
    with pytest.raises(DescriptionError) as info:
        read_urdf(path)
    assert DOCTYPE_MESSAGE in str(info.value)
    assert "root:" not in str(info.value)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-be", "utf-32"])
def test_doctype_in_a_non_ascii_encoding_is_refused(encoding):
    """A DOCTYPE hidden by a UTF-16/32 encoding is refused too, with the same message."""
    text = f'<?xml version="1.0" encoding="{encoding.upper()}"?>\n{SMALL_LAUGHS_BODY}'
    with pytest.raises(DescriptionError, match=DOCTYPE_MESSAGE):
        read_urdf_text(text.encode(encoding), None)


def test_doctype_hidden_by_utf7_is_refused():
    """A DOCTYPE written in UTF-7 base64 (no '<!DOCTYPE' bytes at all) is refused."""
    prolog = SMALL_LAUGHS_BODY[: SMALL_LAUGHS_BODY.index("<robot")]
    hidden = "+" + base64.b64encode(prolog.encode("utf-16-be")).decode().rstrip("=") + "-"
    data = (
        b'<?xml version="1.0" encoding="UTF-7"?>\n'
        + hidden.encode()
        + b'<robot name="&b;"><link name="x"/></robot>'
    )
    assert b"DOCTYPE" not in data
    with pytest.raises(DescriptionError, match=DOCTYPE_MESSAGE):
        read_urdf_text(data, None)


def test_malformed_xml_is_a_description_error(tmp_path):
    """Unbalanced tags give 'malformed URDF XML' naming the file."""
    path = _write(tmp_path, '<robot name="r"><link name="base"></robot>')
    with pytest.raises(DescriptionError) as info:
        read_urdf(path)
    assert str(info.value).startswith(f"{path}: malformed URDF XML: ")


def test_root_other_than_robot_is_refused():
    """A well-formed document whose root is not <robot> is refused, naming the root."""
    with pytest.raises(DescriptionError) as info:
        read_urdf_text('<sdf version="1.6"><model name="m"/></sdf>', None, "model.urdf")
    assert str(info.value) == "model.urdf: URDF root element must be <robot>, got <sdf>"


def test_unreadable_urdf_is_a_description_error(tmp_path):
    """A URDF path that cannot be read gives a DescriptionError naming it."""
    path = tmp_path / "absent.urdf"
    with pytest.raises(DescriptionError) as info:
        read_urdf(path)
    assert str(info.value) == f"{path}: cannot read URDF: No such file or directory"


@pytest.mark.parametrize(
    "filename",
    ["package://../../../etc/passwd", "../outside.stl", "meshes/../../outside.stl", "file://../x.stl"],
)
def test_mesh_path_climbing_out_is_refused(tmp_path, filename):
    """A mesh path with '..' is refused as climbing out of the description folder."""
    folder = tmp_path / "robot"
    folder.mkdir()
    (tmp_path / "outside.stl").write_bytes(ROD_STL.read_bytes())
    path = _write(folder, _mesh_urdf(filename))
    with pytest.raises(DescriptionError) as info:
        read_urdf(path)
    msg = str(info.value)
    assert f"link arm visual: mesh path {filename!r} climbs out of the description folder" in msg
    assert str(folder.resolve()) in msg


@pytest.mark.parametrize("scheme", ["", "file://"])
def test_absolute_mesh_path_outside_is_refused(tmp_path, scheme):
    """An absolute mesh path outside the folder is refused, even when the file exists."""
    folder = tmp_path / "robot"
    folder.mkdir()
    outside = tmp_path / "outside.stl"
    outside.write_bytes(ROD_STL.read_bytes())
    filename = f"{scheme}{outside}"
    path = _write(folder, _mesh_urdf(filename))
    with pytest.raises(DescriptionError) as info:
        read_urdf(path)
    assert f"mesh path {filename!r} points outside the description folder" in str(info.value)


def test_symlink_leading_outside_is_refused(tmp_path):
    """A mesh reached through a symlink that leaves the folder is refused."""
    folder = tmp_path / "robot"
    folder.mkdir()
    (tmp_path / "outside.stl").write_bytes(ROD_STL.read_bytes())
    (folder / "link.stl").symlink_to(tmp_path / "outside.stl")
    path = _write(folder, _mesh_urdf("link.stl"))
    with pytest.raises(DescriptionError, match="points outside the description folder"):
        read_urdf(path)


@pytest.mark.skipif(not ROD_STL.is_file(), reason="example-parallel-robots corpus absent")
@pytest.mark.parametrize(
    "filename", ["rod.stl", "package:///rod.stl", "package://pkg/rod.stl", "meshes/rod.stl"]
)
def test_existing_mesh_is_resolved_to_an_absolute_path(tmp_path, filename):
    """A mesh inside the folder (plain, package:// or sub-folder) becomes an absolute path."""
    target = tmp_path / ("meshes/rod.stl" if filename.startswith("meshes/") else "rod.stl")
    target.parent.mkdir(exist_ok=True)
    shutil.copy(ROD_STL, target)
    source = read_urdf(_write(tmp_path, _mesh_urdf(filename)))
    assert source.missing_meshes == ()
    assert f'filename="{target.resolve()}"' in source.xml
    assert Path(target.resolve()).is_absolute()


def test_package_name_folder_is_searched(tmp_path):
    """package://pkg/meshes/a.stl is found at <folder>/pkg/meshes/a.stl when not at meshes/a.stl."""
    target = tmp_path / "pkg" / "meshes" / "a.stl"
    target.parent.mkdir(parents=True)
    target.write_bytes(b"solid a\nendsolid a\n")
    source = read_urdf(_write(tmp_path, _mesh_urdf("package://pkg/meshes/a.stl")))
    assert f'filename="{target.resolve()}"' in source.xml


def test_missing_meshes_warn_once_listing_all(tmp_path):
    """Two missing meshes give exactly one MissingMeshWarning that names both files."""
    path = _write(tmp_path, _mesh_urdf("package://meshes/arm.stl", "tool.stl"))
    with pytest.warns(MissingMeshWarning) as record:
        source = read_urdf(path)
    assert len(record) == 1
    assert str(record[0].message) == (
        f"{path}: 2 mesh file(s) missing, loading without those visuals: package://meshes/arm.stl, tool.stl"
    )
    assert source.missing_meshes == ("package://meshes/arm.stl", "tool.stl")
    assert "<mesh" not in source.xml
    assert "<box" in source.xml


def test_many_missing_meshes_are_summarised():
    """More than eight missing meshes: eight are shown and the total is given."""
    names = [f"m{k}.stl" for k in range(10)]
    with pytest.warns(MissingMeshWarning) as record:
        read_urdf_text(_mesh_urdf(*names), None, "big.urdf")
    assert len(record) == 1
    msg = str(record[0].message)
    assert msg.startswith("big.urdf: 10 mesh file(s) missing")
    assert msg.endswith("m6.stl, m7.stl, ... (10 files)")


@pytest.mark.skipif(not ROD_STL.is_file(), reason="example-parallel-robots corpus absent")
def test_loaded_mechanism_keeps_other_visuals_and_drops_missing_ones(tmp_path):
    """Via plm_pin.load: one warning, no geometry for the two missing meshes, the others kept."""
    shutil.copy(ROD_STL, tmp_path / "rod.stl")
    _write(tmp_path, _mesh_urdf("package://meshes/arm.stl", "rod.stl", "tool.stl"))
    (tmp_path / "robot.plm.yaml").write_text("format: plm-pin/1\nactuation: [{joint: j}]\n")
    with pytest.warns(MissingMeshWarning) as record:
        mech = plm_pin.load(tmp_path / "robot.urdf")
    assert len(record) == 1
    assert "2 mesh file(s) missing" in str(record[0].message)
    visuals = mech.visual_model.geometryObjects
    assert len(visuals) == 2  # the base box and the arm's rod.stl
    files = [g.meshPath for g in visuals]
    assert str((tmp_path / "rod.stl").resolve()) in files
    assert not any("arm.stl" in f or "tool.stl" in f for f in files)
    assert {mech.model.frames[g.parentFrame].name for g in visuals} == {"base", "arm"}


def test_collision_of_a_missing_mesh_is_dropped_silently_when_its_visual_exists(tmp_path):
    """A collision whose mesh is missing is removed; the warning counts visuals only."""
    text = _mesh_urdf("gone.stl").replace(
        "</link><joint",
        '<collision><geometry><mesh filename="also_gone.stl"/></geometry></collision></link><joint',
    )
    with pytest.warns(MissingMeshWarning) as record:
        source = read_urdf(_write(tmp_path, text))
    assert len(record) == 1
    assert source.missing_meshes == ("gone.stl",)
    assert "<collision" not in source.xml


def test_text_without_folder_drops_meshes_and_warns_about_visuals_only():
    """With no folder every mesh is dropped; only visual meshes are reported as missing visuals."""
    text = (
        '<robot name="r"><link name="a">'
        '<visual><geometry><mesh filename="v.stl"/></geometry></visual>'
        '<collision><geometry><mesh filename="c.stl"/></geometry></collision>'
        "</link></robot>"
    )
    with pytest.warns(MissingMeshWarning) as record:
        source = read_urdf_text(text, None, "x.urdf")
    assert len(record) == 1
    assert str(record[0].message) == "x.urdf: 1 mesh file(s) missing, loading without those visuals: v.stl"
    assert source.missing_meshes == ("v.stl",)
    assert "<mesh" not in source.xml

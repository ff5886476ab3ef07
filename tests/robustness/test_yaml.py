"""YAML denial of service: alias chains, huge files and huge values are refused fast, with short messages."""

from __future__ import annotations

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from plm_pin import load
from plm_pin._yaml import MAX_BYTES, MAX_NODES, load_yaml
from plm_pin.exceptions import DescriptionError, InvalidInput
from plm_pin.sweep import load_config
from tests.robustness.conftest import budget, fourbar_files, fourbar_sidecar, one_line_error, run_cli

MESSAGE_MAX = 700
"""Longest message any refused input may produce [characters]: values are quoted cut short."""


def chain(depth: int, width: int) -> str:
    """A flow list of ``depth`` anchored lists, each holding ``width`` aliases of the one before.

    It stands for about ``width ** depth`` nodes in ``12 * depth * width`` characters.
    """
    items = [f"&a0 [{', '.join(['lol'] * width)}]"]
    items += [f"&a{i} [{', '.join([f'*a{i - 1}'] * width)}]" for i in range(1, depth)]
    return "[" + ", ".join(items) + "]"


def expanded(depth: int, width: int) -> int:
    """Nodes the chain stands for, every alias expanded (counted independently of plm_pin._yaml)."""
    size = width + 1  # a0: the list and its scalars
    total = size
    for _ in range(1, depth):
        size = width * size + 1
        total += size
    return total + 1  # the outer list


SIDECAR_PLACES = {
    "name": lambda d, b: d.__setitem__("name", b),
    "source": lambda d, b: d.__setitem__("source", b),
    "format": lambda d, b: d.__setitem__("format", b),
    "closure frames": lambda d, b: d["closures"][0].__setitem__("frames", b),
    "closure frame": lambda d, b: d["closures"][0]["frames"].__setitem__(0, b),
    "closure name": lambda d, b: d["closures"][0].__setitem__("name", b),
    "closure type": lambda d, b: d["closures"][0].__setitem__("type", b),
    "actuation joint": lambda d, b: d["actuation"][0].__setitem__("joint", b),
    "actuation limits": lambda d, b: d["actuation"][0].__setitem__("limits", b),
    "end_effector frame": lambda d, b: d["end_effector"].__setitem__("frame", b),
    "end_effector task": lambda d, b: d["end_effector"].__setitem__("task", b),
    "gravity": lambda d, b: d.__setitem__("gravity", b),
    "reference value": lambda d, b: d["reference"].__setitem__("crank_pivot", b),
    "an unknown key": lambda d, b: d.__setitem__("extra", b),
}
"""Where a hostile value goes in the four-bar sidecar: every field the issue names, and more."""


def sidecar_with(place: str, fragment: str) -> str:
    """The four-bar sidecar text with ``fragment`` (YAML text) at ``place``."""
    data = fourbar_sidecar()
    SIDECAR_PLACES[place](data, "__HOSTILE__")
    text = yaml.safe_dump(data, sort_keys=False)
    assert "__HOSTILE__" in text
    return text.replace("__HOSTILE__", fragment)


@pytest.mark.parametrize("place", sorted(SIDECAR_PLACES))
@pytest.mark.parametrize(("depth", "width"), [(9, 10), (6, 8), (5, 10), (17, 2), (3, 47)])
def test_an_alias_bomb_anywhere_in_a_sidecar_is_refused(tmp_path, place, depth, width):
    """An alias chain standing for more than MAX_NODES nodes is refused before it is built, naming aliases."""
    assert expanded(depth, width) > MAX_NODES
    urdf = fourbar_files(tmp_path, sidecar=sidecar_with(place, chain(depth, width)))
    with pytest.raises(DescriptionError) as err:
        load(urdf)
    assert str(err.value) == (
        f"{urdf.with_name('fourbar.plm.yaml')}: the document stands for more than {MAX_NODES} nodes once its "
        "aliases (*name) are expanded; aliases that repeat large parts are refused"
    )


@budget
@given(
    place=st.sampled_from(sorted(SIDECAR_PLACES)),
    depth=st.integers(1, 12),
    width=st.integers(1, 12),
)
def test_any_alias_chain_in_a_sidecar_is_refused_or_reported_briefly(tmp_path_factory, place, depth, width):
    """Small chains load as data, then are refused as wrong values with a short message; big ones as bombs."""
    urdf = fourbar_files(tmp_path_factory.mktemp("s"), sidecar=sidecar_with(place, chain(depth, width)))
    with pytest.raises(DescriptionError) as err:
        load(urdf)
    message = str(err.value)
    assert len(message) < MESSAGE_MAX
    assert ("aliases (*name) are expanded" in message) == (expanded(depth, width) > MAX_NODES)


EPR_PLACES = ("closed_loop", "type", "name_mot")


@pytest.mark.parametrize("key", EPR_PLACES)
@pytest.mark.parametrize(("depth", "width"), [(9, 10), (17, 2)])
def test_an_alias_bomb_in_an_example_parallel_robots_sidecar_is_refused(tmp_path, key, depth, width):
    """robot.yaml (closed_loop, type, name_mot) is read by the same capped reader."""
    folder = tmp_path / "robot"
    folder.mkdir()
    (folder / "robot.urdf").write_text("<robot name='r'><link name='a'/></robot>")
    entries = {"closed_loop": "[['a', 'a']]", "type": "['6d']", "name_mot": "['m']"}
    entries[key] = chain(depth, width)
    (folder / "robot.yaml").write_text("".join(f"{k}: {v}\n" for k, v in entries.items()))
    with pytest.raises(
        DescriptionError, match=r"robot\.yaml: the document stands for more than 100000 nodes"
    ):
        load(folder)


SWEEP_PLACES = ("mechanism", "parameters", "poses", "metrics", "options", "base")


@pytest.mark.parametrize("key", SWEEP_PLACES)
def test_an_alias_bomb_in_a_sweep_configuration_is_refused(tmp_path, key):
    """A sweep configuration is read by the same capped reader (InvalidInput naming the file)."""
    config = tmp_path / "sweep.yaml"
    config.write_text(f"format: plm-pin-sweep/1\n{key}: {chain(9, 10)}\n")
    with pytest.raises(InvalidInput) as err:
        load_config(config)
    assert str(err.value).startswith(
        f"{config}: not valid YAML (the document stands for more than 100000 nodes"
    )


@pytest.mark.parametrize(
    "filler",
    ["# a comment\n", "source: x\n", "reference: {a: 1}\n", "a" * 1000 + "\n"],
)
def test_a_file_over_the_size_cap_is_refused_without_parsing(tmp_path, filler):
    """A sidecar or configuration larger than MAX_BYTES is refused by size, whatever it holds."""
    text = "format: plm-pin/1\n" + filler * (MAX_BYTES // len(filler) + 1)
    urdf = fourbar_files(tmp_path, sidecar=text)
    with pytest.raises(
        DescriptionError, match=r"the file is larger than 256 KiB, the most read from a YAML file"
    ):
        load(urdf)
    config = tmp_path / "sweep.yaml"
    config.write_text(text)
    with pytest.raises(InvalidInput, match=r"not valid YAML \(the file is larger than 256 KiB"):
        load_config(config)


@budget
@given(
    place=st.sampled_from(sorted(SIDECAR_PLACES)),
    size=st.integers(1_000, 50_000),
    kind=st.sampled_from(["string", "list", "mapping"]),
)
def test_a_huge_value_is_quoted_cut_short(tmp_path_factory, place, size, kind):
    """However large a wrong value is (under the size cap), the message quoting it stays short."""
    fragment = {
        "string": "x" * size,
        "list": "[" + ", ".join(["1"] * (size // 3)) + "]",
        "mapping": "{" + ", ".join(f"k{i}: 1" for i in range(size // 8)) + "}",
    }[kind]
    urdf = fourbar_files(tmp_path_factory.mktemp("s"), sidecar=sidecar_with(place, fragment))
    try:
        load(urdf)
    except DescriptionError as err:
        assert len(str(err)) < MESSAGE_MAX
    else:  # a long source or name is legal
        assert place in ("source", "name", "closure name") and kind == "string"


@pytest.mark.parametrize(
    "tag",
    [
        "!!python/object/apply:os.system ['true']",
        "!!python/name:os.system",
        "!!python/object:builtins.dict {}",
        "!!binary aGVsbG8=",
        "!custom x",
    ],
)
def test_yaml_tags_build_no_python_objects(tmp_path, tag):
    """Tags naming Python objects are refused as malformed YAML; plain data tags give a wrong-type error."""
    urdf = fourbar_files(tmp_path, sidecar=sidecar_with("name", tag))
    with pytest.raises(DescriptionError, match=r"(malformed YAML at line \d+, column \d+|name must be a)"):
        load(urdf)


def test_the_c_parser_is_used_where_pyyaml_has_it():
    """LibYAML's safe loader reads the files when PyYAML was built with it (fast on large files)."""
    from plm_pin import _yaml

    expected = yaml.CSafeLoader if getattr(yaml, "__with_libyaml__", False) else yaml.SafeLoader
    assert _yaml._loader() is expected
    assert load_yaml("a: [1, 2]\nb: &x {c: 1}\nd: *x\n") == {"a": [1, 2], "b": {"c": 1}, "d": {"c": 1}}


def test_plm_pin_check_refuses_the_issue_bomb_in_one_line(tmp_path):
    """The issue's case: a ~700-byte sidecar whose name is a nine-level chain; `check` says so in one line."""
    text = sidecar_with("name", chain(9, 10))
    assert len(text.encode()) < 1200
    urdf = fourbar_files(tmp_path, sidecar=text)
    line = one_line_error(run_cli("check", str(urdf)))
    assert line.endswith("aliases that repeat large parts are refused")


def many(kind: str) -> str:
    """Sidecar texts whose error lists or names something huge (within the size cap)."""
    base = yaml.safe_dump(fourbar_sidecar(), sort_keys=False)
    if kind == "unknown keys":
        return base + "".join(f"k{i}: 1\n" for i in range(5000))
    if kind == "a long reference key":
        data = fourbar_sidecar()
        data["reference"] = {"j" * 100_000: 1.0}
        return yaml.safe_dump(data, sort_keys=False)
    if kind == "duplicate closures":
        return base.replace(
            "closures:\n",
            "closures:\n" + "- {name: c, frames: [coupler_tip, rocker_tip], type: point}\n" * 3000,
            1,
        )
    return base.replace("actuation:\n", "actuation:\n" + "- {joint: crank_pivot}\n" * 5000, 1)


@pytest.mark.parametrize(
    "kind", ["unknown keys", "a long reference key", "duplicate closures", "duplicate joints"]
)
def test_a_long_list_of_wrong_names_is_quoted_cut_short(tmp_path, kind):
    """Thousands of unknown keys or duplicates, or a 100 kB name, give a message of bounded length."""
    urdf = fourbar_files(tmp_path, sidecar=many(kind))
    with pytest.raises(DescriptionError) as err:
        load(urdf)
    assert len(str(err.value)) < MESSAGE_MAX


def test_a_sweep_configuration_with_thousands_of_unknown_keys_is_quoted_cut_short(tmp_path):
    """The sweep configuration's unknown keys are quoted cut short too."""
    config = tmp_path / "sweep.yaml"
    config.write_text("".join(f"k{i}: 1\n" for i in range(5000)))
    with pytest.raises(InvalidInput, match=r"unknown key\(s\) \[") as err:
        load_config(config)
    assert len(str(err.value)) < MESSAGE_MAX

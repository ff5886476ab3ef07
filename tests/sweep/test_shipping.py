"""Sweeps of a Mechanism given as it is (loaded from a URDF path): shipped to Dask workers, not rebuilt.

The mechanism is the 6-UPS Stewart platform of tests/textbook.py written to disk and loaded
with :func:`plm_pin.load`; its manipulability is checked against the closed form |det J| of
the textbook, the cluster's results against this process's bit for bit, and the workers are
watched: they unpickle Mechanisms, they never construct one.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr

import plm_pin
from plm_pin import InvalidInput, StoreMismatch
from plm_pin.core.mechanism import Mechanism
from plm_pin.sweep import make_spec, sweep
from plm_pin.sweep.spec import mechanism_digest
from plm_pin.sweep.store import MANIFEST
from tests import textbook as tb
from tests.sweep.conftest import THETAS, fragile_2prrrp

XS = [0.0, 0.01, 0.02]
"""Platform x of the pose grid [m]; the other coordinates are those of tb.STEWART_POSE."""


def _stewart_sweep(mech: Any, **kwargs: Any) -> Any:
    return sweep(
        mech, poses={"x": XS}, pose=list(tb.STEWART_POSE), metrics=["manipulability", "singularity"], **kwargs
    )


@pytest.fixture()
def stewart(tmp_path):
    """The 6-UPS written to a folder and loaded from its URDF path (not a preset)."""
    return tb.stewart(tmp_path / "stewart")


def test_a_loaded_mechanism_sweeps_its_poses_with_the_closed_form(stewart):
    """sweep(Mechanism) evaluates that Mechanism itself: w = |det J| of the textbook at every pose."""
    result = _stewart_sweep(stewart)
    assert result.complete and result.spec.built is stewart and result.spec.n_points == 1
    for k, x in enumerate(XS):
        _, J = tb.stewart_legs((x, *tb.STEWART_POSE[1:]))
        assert result.dataset["manipulability"].values[k] == pytest.approx(abs(np.linalg.det(J)), rel=1e-9)
    attrs = result.dataset.attrs
    assert attrs["mechanism"] == "stewart" and attrs["mechanism_digest"] == mechanism_digest(stewart)
    assert attrs["mechanism_source"] == stewart.source == str(Path(stewart.source).resolve())
    assert json.loads(attrs["spec"])["digest"] == mechanism_digest(stewart)


def test_parameters_or_base_with_a_mechanism_are_refused(stewart):
    """A Mechanism has no builder parameters: varying or fixing any is refused before any work."""
    message = r"^parameters and base are builder parameters; stewart is a Mechanism, which has none: "
    with pytest.raises(InvalidInput, match=message):
        make_spec(stewart, {"u0a.x": [0.44, 0.5]}, {"x": XS})
    with pytest.raises(InvalidInput, match=message):
        make_spec(stewart, None, {"x": XS}, base={"platform.mass": 3.0})


def test_digest_follows_the_mechanism_not_the_process(stewart, tmp_path):
    """Loading the same files again, here or in another process, gives the same digest; another model not."""
    again = plm_pin.load(stewart.source)
    assert mechanism_digest(again) == mechanism_digest(stewart)
    code = (
        "import plm_pin, sys; from plm_pin.sweep.spec import mechanism_digest; "
        "print(mechanism_digest(plm_pin.load(sys.argv[1])))"
    )
    other = subprocess.run(
        [sys.executable, "-c", code, stewart.source], capture_output=True, text=True, check=True
    )
    assert other.stdout.strip() == mechanism_digest(stewart)
    spun = tb.stewart(tmp_path / "spun", spherical_base=True)  # idle struts: gauges in its model
    assert spun.idle_mobility == 6 and mechanism_digest(spun) != mechanism_digest(stewart)
    assert mechanism_digest(plm_pin.load(spun.source)) == mechanism_digest(spun)


def test_resume_takes_the_same_mechanism_and_refuses_another(stewart, tmp_path):
    """A stored Mechanism sweep resumes from a fresh load of its files; another model so named is refused."""
    store = tmp_path / "store"
    first = _stewart_sweep(stewart, store=store)
    manifest = json.loads((store / MANIFEST).read_text())
    assert manifest["spec"]["mechanism"] == "stewart" and manifest["source"] == stewart.source
    assert manifest["spec"]["digest"] == mechanism_digest(stewart)
    again = _stewart_sweep(plm_pin.load(stewart.source), store=store)
    assert again.loaded == 1 and again.computed == ()
    xr.testing.assert_identical(again.dataset, first.dataset)
    other = tb.stewart(tmp_path / "other", spherical_base=True)  # also named "stewart"
    with pytest.raises(StoreMismatch) as err:
        _stewart_sweep(other, store=store)
    assert err.value.differences == ("digest",)


def test_a_description_path_whose_file_changed_is_refused_on_resume(stewart, tmp_path):
    """sweep(path): the digest of the mechanism built from the file is in the key: an edit is refused."""
    store, path = tmp_path / "store", stewart.source
    _stewart_sweep(path, store=store)
    assert _stewart_sweep(path, store=store).loaded == 1
    tb.stewart(Path(path).parent, spherical_base=True)  # the same path, another description
    with pytest.raises(StoreMismatch) as err:
        _stewart_sweep(path, store=store)
    assert err.value.differences == ("digest",)


_SEEN: dict[str, int] = {}
"""On a worker: Mechanisms constructed (built or loaded) and unpickled there while watched."""


def _watch() -> None:
    """On a worker: count Mechanism constructions and unpicklings from now on."""
    _SEEN.update(init=0, setstate=0)
    init, setstate = Mechanism.__init__, Mechanism.__setstate__

    def counted_init(self: Mechanism, *args: Any, **kwargs: Any) -> None:
        _SEEN["init"] += 1
        init(self, *args, **kwargs)

    def counted_setstate(self: Mechanism, state: dict[str, Any]) -> None:
        _SEEN["setstate"] += 1
        setstate(self, state)

    counted_init.original = init  # type: ignore[attr-defined]
    counted_setstate.original = setstate  # type: ignore[attr-defined]
    Mechanism.__init__ = counted_init  # type: ignore[method-assign]
    Mechanism.__setstate__ = counted_setstate  # type: ignore[method-assign]


def _unwatch() -> dict[str, int]:
    """On a worker: stop counting; what was counted."""
    Mechanism.__init__ = Mechanism.__init__.original  # type: ignore[attr-defined, method-assign]
    Mechanism.__setstate__ = Mechanism.__setstate__.original  # type: ignore[attr-defined, method-assign]
    return dict(_SEEN)


def _on_workers(client: Any, run: Any) -> tuple[Any, dict[str, int]]:
    """``run()``'s result, and the Mechanisms the workers constructed and unpickled meanwhile (summed)."""
    client.run(_watch)
    try:
        out = run()
    finally:
        seen = client.run(_unwatch)
    assert len(seen) == 2
    return out, {k: sum(s[k] for s in seen.values()) for k in ("init", "setstate")}


@pytest.mark.slow
def test_a_loaded_mechanism_is_shipped_to_the_workers_not_rebuilt(cluster, stewart):
    """On 2 workers: bit-identical results; the workers unpickle the Mechanism and construct none.

    The description files are deleted before the cluster runs: a worker could not load them.
    """
    distributed = pytest.importorskip("distributed")
    local = _stewart_sweep(stewart)
    shutil.rmtree(Path(stewart.source).parent)
    with distributed.Client(cluster, set_as_default=False) as client:
        remote, seen = _on_workers(client, lambda: _stewart_sweep(stewart, scheduler=client))
    assert remote.complete and remote.computed == ((0, 0),)
    xr.testing.assert_identical(remote.dataset, local.dataset)
    assert seen["init"] == 0 and seen["setstate"] >= 1


@pytest.mark.slow
def test_a_single_point_is_shipped_and_several_are_built_by_the_workers(cluster):
    """A builder sweep of one point ships the mechanism built for the checks; of 2 points, each worker builds.

    Building on the workers is the measured choice for parameter points (see
    plm_pin/sweep/execution.py): the client's check of the first point is not shipped then.
    """
    distributed = pytest.importorskip("distributed")
    poses = {"y": [0.08], "rz": THETAS[14:19]}
    with distributed.Client(cluster, set_as_default=False) as client:
        for plates, built in (([0.035], 0), ([0.035, 0.05], 2)):
            args = (fragile_2prrrp, {"half_plate": plates}, poses, ["manipulability"])
            local = sweep(*args, pose=(0.0, 0.08, 0.0), chunk=1)
            remote, seen = _on_workers(
                client, lambda a=args: sweep(*a, pose=(0.0, 0.08, 0.0), chunk=1, scheduler=client)
            )
            xr.testing.assert_identical(remote.dataset, local.dataset)
            assert seen["init"] == built, plates
            assert (seen["setstate"] >= 1) == (built == 0), plates

"""Optional dependencies of the sweeps (the ``sweep`` extra), imported when first needed."""

from __future__ import annotations

import importlib
from types import ModuleType

DISTRIBUTIONS = {
    "dask": "dask",
    "distributed": "distributed",
    "xarray": "xarray",
    "pyarrow": "pyarrow",
    "pyarrow.parquet": "pyarrow",
    "filelock": "filelock",
}
"""The distribution that provides each module imported through :func:`require`."""


def require(module: str) -> ModuleType:
    """Import ``module``, or say which package is missing and how to install it.

    Raises:
        ImportError: with ``pip install 'plm-pin[sweep]'`` in the message.
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        package = DISTRIBUTIONS.get(module, module.split(".")[0])
        raise ImportError(
            f"plm_pin.sweep needs {package}, which is not installed: pip install 'plm-pin[sweep]' "
            f"(or pip install {package})"
        ) from exc

"""Shared fixtures of the figure tests."""

from __future__ import annotations

import pytest


@pytest.fixture
def close_figures():
    """Close the figures a test opens."""
    import matplotlib.pyplot as plt

    yield
    plt.close("all")

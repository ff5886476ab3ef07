"""The version of plm_pin: the one place it is written (read by hatch at build)."""

__version__ = "0.2.0"

"""``python -m plm_pin``: the ``plm-pin`` command line."""

from .cli import main

main()

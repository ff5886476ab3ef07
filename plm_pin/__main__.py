"""``python -m plm_pin``: the ``plm-pin`` command line."""

from .cli import main

if __name__ == "__main__":  # imported (e.g. by pkgutil.walk_packages), it does nothing
    main()

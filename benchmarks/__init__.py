"""The benchmark harness (``make bench``): in the checkout, not in the installed package."""

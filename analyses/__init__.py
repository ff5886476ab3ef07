"""The paper studies: one module per paper or design question, each filling a report (plm_pin.report)."""

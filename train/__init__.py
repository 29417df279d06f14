"""Training entry point: ``python -m train --config ... --data ... --out ...`` (logic in relightnet.model)."""

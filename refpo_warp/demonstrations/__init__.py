"""Demonstration datasets (Minari format), collecting them from a policy, and behaviour cloning (docs/finetuning.md)."""

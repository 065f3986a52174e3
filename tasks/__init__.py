"""Task families. Importing this package registers every task id (cheaply: env modules load on first use)."""

from tasks import dmc, gridworld, humanoid  # noqa: F401  (each family's __init__ registers its ids)

"""The Ray backend of the executor: one Ray task per run (``backend.py`` on the head, ``node.py`` on the nodes)."""

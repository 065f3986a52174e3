"""Glue between the project's algorithms and other frameworks' task systems (``mjlab/``). A subpackage imports its
framework at the top, which the project does not depend on: it is loaded by that framework (an entry point), never
by the rest of refpo_warp."""

"""The package list (everything else is in pyproject.toml): refpo_warp's packages and the task families of tasks/,
which install under refpo_warp.tasks (package-dir in pyproject.toml). Found, not listed: a new family needs no edit.
Namespace discovery includes the data folders (MJCF models, shipped clips) as packages of their package data."""

from setuptools import find_namespace_packages, setup

EXCLUDE = ["*__pycache__*"]
packages = find_namespace_packages(include=["refpo_warp*"], exclude=EXCLUDE)
packages += [f"refpo_warp.{p}" for p in find_namespace_packages(include=["tasks*"], exclude=EXCLUDE)]
setup(packages=packages)

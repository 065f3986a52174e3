"""The package list (everything else is in pyproject.toml): refpo_warp's packages, the task families of tasks/ and the
shipped YAML files of configs/, which install under refpo_warp.tasks and refpo_warp.configs (package-dir in
pyproject.toml). Found, not listed: a new family needs no edit. Namespace discovery includes the data folders (MJCF
models, shipped clips, config folders) as packages of their package data."""

from setuptools import find_namespace_packages, setup

EXCLUDE = ["*__pycache__*"]
packages = find_namespace_packages(include=["refpo_warp*"], exclude=EXCLUDE)
for folder in ("tasks", "configs"):
    packages += [f"refpo_warp.{p}" for p in find_namespace_packages(include=[f"{folder}*"], exclude=EXCLUDE)]
setup(packages=packages)

"""Package discovery for the three layers (metadata lives in pyproject.toml).

The repository keeps ``rdmp_gym/``, ``envs/`` and ``agents/`` at the top level; installed, they are
``rdmp_gym``, ``rdmp_gym.envs`` and ``rdmp_gym.agents`` (``package_dir``). Every package below each
folder is found automatically, so a new subpackage cannot be left out of the wheel.
"""

from setuptools import find_namespace_packages, setup

LAYERS = {"rdmp_gym": "rdmp_gym", "rdmp_gym.envs": "envs", "rdmp_gym.agents": "agents"}


def layer_packages() -> list[str]:
    """Every package (namespace folders such as ``envs/assets`` included) under the layer folders."""
    packages = []
    for name, folder in LAYERS.items():
        found = find_namespace_packages(folder, exclude=["*__pycache__*", "*.egg-info*"])
        packages += [name, *(f"{name}.{package}" for package in found)]
    return sorted(set(packages))


setup(packages=layer_packages(), package_dir=LAYERS)

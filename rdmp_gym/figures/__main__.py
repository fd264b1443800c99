"""``python -m rdmp_gym.figures --out DIR``: :func:`rdmp_gym.figures.paper.main`."""

from .paper import main

main()

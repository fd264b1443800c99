"""Figures (matplotlib, the ``plots`` extra, loaded only when a figure is drawn): the top layer of the core.

* :mod:`~rdmp_gym.figures.plots`: figures in the style of the paper, each function returns a ``Figure``;
* :mod:`~rdmp_gym.figures.paper`: the paper's figures and the stop's and the rhythm's, written as PNG files
  (``python -m rdmp_gym.figures --out figures/``).
"""

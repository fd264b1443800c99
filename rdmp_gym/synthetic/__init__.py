"""Synthetic data with known truth, for tests, benchmarks, examples and figures; nothing below imports it.

* :mod:`~rdmp_gym.synthetic.demonstrations`: the paper's wiping demonstrations and realistic recordings of a
  person's rhythmic manipulation;
* :mod:`~rdmp_gym.synthetic.pose`: those recordings with a tool orientation;
* :mod:`~rdmp_gym.synthetic.sessions`: recordings with several sessions;
* :mod:`~rdmp_gym.synthetic.smoothness`: smooth test signals with exact derivatives, and how far a reproduction's
  acceleration and jerk are from them.
"""

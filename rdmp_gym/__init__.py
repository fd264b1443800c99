"""rdmp-gym: rhythmic DMPs that encode a periodic motion and its transient start (Ernesti et al. 2012).

The core (this package) depends on numpy and scipy only: ``import rdmp_gym`` loads neither gymnasium, MuJoCo,
matplotlib nor torch, and sets no environment variable. ``rdmp_gym.envs`` (gymnasium + MuJoCo) and
``rdmp_gym.agents`` (learners) are separate layers; ``import rdmp_gym.envs`` (or
``gym.register_envs(rdmp_gym.envs)``) registers the environments. The figures (:mod:`rdmp_gym.figures.plots`,
:mod:`rdmp_gym.figures.paper`) need matplotlib, the ``plots`` extra.
"""

from .dmp.basis import BasisSet, Fading
from .dmp.canonical import CanonicalSystem
from .dmp.classic import PeriodicDMP
from .dmp.parameters import GROUPS, ParameterLayout
from .dmp.rhythmic import DMPStepper, RhythmicDMP, StopRequest, TransientStart
from .dmp.serialization import load_dmp, save_dmp
from .dmp.settings import DEFAULT_FIT, PAPER_FIT, PUBLISHED_ENV_FIT, FitSettings
from .dmp.sweep import Sweep
from .signals.demonstrations import Demonstration, SyntheticTruth
from .signals.segmentation import Segmentation, phase_shift, segment
from .synthetic.demonstrations import multi_transient_demonstrations, wiping_demonstration

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_FIT",
    "GROUPS",
    "PAPER_FIT",
    "PUBLISHED_ENV_FIT",
    "BasisSet",
    "CanonicalSystem",
    "DMPStepper",
    "Demonstration",
    "Fading",
    "FitSettings",
    "ParameterLayout",
    "PeriodicDMP",
    "RhythmicDMP",
    "Segmentation",
    "StopRequest",
    "Sweep",
    "SyntheticTruth",
    "TransientStart",
    "load_dmp",
    "multi_transient_demonstrations",
    "phase_shift",
    "save_dmp",
    "segment",
    "wiping_demonstration",
]

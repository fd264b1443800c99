"""rdmp-gym: rhythmic DMPs that encode a periodic motion and its transient start (Ernesti et al. 2012).

The core (this package) depends on numpy and scipy only: ``import rdmp_gym`` loads neither gymnasium, MuJoCo,
matplotlib nor torch, and sets no environment variable. ``rdmp_gym.envs`` (gymnasium + MuJoCo) and
``rdmp_gym.agents`` (learners) are separate layers; ``import rdmp_gym.envs`` (or
``gym.register_envs(rdmp_gym.envs)``) registers the environments. The figures (:mod:`rdmp_gym.plots`,
:mod:`rdmp_gym.figures`) need matplotlib, the ``plots`` extra.
"""

from .basis import BasisSet, Fading
from .canonical import CanonicalSystem
from .classic import PeriodicDMP
from .demonstrations import Demonstration, SyntheticTruth
from .dmp import DMPStepper, RhythmicDMP, StopRequest, TransientStart
from .parameters import GROUPS, ParameterLayout
from .segmentation import Segmentation, phase_shift, segment
from .serialization import load_dmp, save_dmp
from .settings import DEFAULT_FIT, PAPER_FIT, PUBLISHED_ENV_FIT, FitSettings
from .sweep import Sweep
from .synthetic import multi_transient_demonstrations, wiping_demonstration

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

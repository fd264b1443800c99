"""rdmp-gym: rhythmic DMPs that encode a periodic motion and its transient start (Ernesti et al. 2012).

The core (this package) depends on numpy and scipy only. ``rdmp_gym.envs`` (gymnasium + MuJoCo) and
``rdmp_gym.agents`` (learners) are separate layers; importing ``rdmp_gym`` registers the environments
when gymnasium and mujoco are installed.
"""

from .basis import BasisSet, Fading
from .canonical import CanonicalSystem
from .classic import PeriodicDMP
from .demonstrations import Demonstration, SyntheticTruth, multi_transient_demonstrations, wiping_demonstration
from .dmp import DMPStepper, RhythmicDMP, TransientStart
from .parameters import GROUPS, ParameterLayout
from .segmentation import Segmentation, phase_shift, segment
from .serialization import load_dmp, save_dmp
from .sweep import Sweep

__version__ = "0.1.0"

__all__ = [
    "GROUPS",
    "BasisSet",
    "CanonicalSystem",
    "DMPStepper",
    "Demonstration",
    "Fading",
    "ParameterLayout",
    "PeriodicDMP",
    "RhythmicDMP",
    "Segmentation",
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

try:  # the environment layer is optional: it needs gymnasium and mujoco
    from . import envs as _envs  # noqa: F401  (registers rdmp_gym/ArmarWipe-v1)
except ImportError:  # pragma: no cover - exercised only without the extras
    pass

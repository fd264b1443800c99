"""The drumming task: both robots strike a drum in time with a metronome whose tempo changes, then stop at rest.

:class:`DrumTask` is its description (:mod:`rdmp_gym.envs.tasks.description`); ``rdmp_gym/ArmarDrum-v1`` and
``rdmp_gym/PandaDrum-v1`` (and their step twins) run it. :class:`RetuningDrumTask` is its second version
(``rdmp_gym/ArmarDrum-v2``, ``rdmp_gym/PandaDrum-v2``): the rhythm follower's ``ear`` and ``tempo`` values let a
policy make it follow the tempo it hears, and the cycle-level face hears the tempo.
"""

from .context import DrumContext, DrumContextSpec
from .demonstration import drumming_demonstration
from .metronome import Metronome
from .retuning import RetuningDrumTask
from .strikes import Strikes, score_beats
from .task import DrumTask

__all__ = ["DrumContext", "DrumContextSpec", "DrumTask", "Metronome", "RetuningDrumTask", "Strikes",
           "drumming_demonstration", "score_beats"]

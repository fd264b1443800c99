"""The ``rdmp-gym`` command: ``train``, ``evaluate``, ``fit``, ``cycles`` and ``main`` (the job of ``make run``).

This launcher imports a command's module only when that command runs: ``fit``
(:mod:`rdmp_gym.agents.fit_command`) needs only the core install, ``train``, ``evaluate`` and ``main``
(:mod:`rdmp_gym.agents.run_commands`) the ``agents`` extra, and say so when it is missing::

    rdmp-gym train --out runs/bbrl                      # the main job's learner (bbrl) on the current task
    rdmp-gym train --agent cpi2 --updates 30 --options.sigma 0.2 --out runs/cpi2
    rdmp-gym train --env-option style 2 --env-option groups '["periodic", "amplitude"]' --out runs/style2
    rdmp-gym train --agent cmaes --env InvertedPendulum-v5 --out runs/pendulum   # a step-based env, wrapped
    rdmp-gym train --out runs/bbrl --resume --updates 300       # continue (and extend) a run
    rdmp-gym evaluate runs/bbrl --episodes 20 --video   # final policy on the 20 test contexts
    rdmp-gym fit --demo recording.csv --time-column time --rate 100 --plot
    rdmp-gym cycles --env rdmp_gym/PandaWipe-v3 --out runs/cycles   # a policy that reacts cycle by cycle
    rdmp-gym main --out runs/main

Every command's flags are derived with `tyro <https://brentyi.github.io/tyro/>`_ from typed dataclasses
(:class:`~rdmp_gym.agents.run_commands.TrainCommand`, :class:`~rdmp_gym.agents.fit_command.FitCommand`, ...); a
training run's flags are the fields of :class:`~rdmp_gym.agents.train_config.TrainConfig`, and the env's settings are
``--env-option KEY VALUE`` pairs (repeatable, JSON values).
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

from rdmp_gym import __version__

from . import EXTRA_MODULES
from .errors import WorkerError

__all__ = ["COMMANDS", "Command", "main", "parse"]


class Command(NamedTuple):
    """A command of the launcher: where it lives and what it does."""

    module: str
    """its module in this package"""
    function: str
    """the function that runs it (takes the command line after the command's name)"""
    about: str
    """what it does (the first line of its help)"""
    needs_extra: bool
    """whether it needs the agents extra"""
    parser: str
    """the function that parses its command line into its dataclass without running it"""


COMMANDS: dict[str, Command] = {
    "train": Command("run_commands", "command_train", "Train an agent: bbrl with the main job's settings on the "
                     "current task, cmaes on a step-based env.", True, "parse_train"),
    "evaluate": Command("run_commands", "command_evaluate",
                        "Evaluate a run's final policy against the imitation on the test contexts.", True,
                        "parse_evaluate"),
    "fit": Command("fit_command", "command_fit", "Fit the rhythmic DMP to a built-in style or to a whole recording "
                   "(rest, approach, rhythm, departure, rest).", False, "parse_fit"),
    "cycles": Command("cycle_command", "command_cycles", "Train a policy that reacts cycle by cycle (cycle-by-cycle "
                      "search, SAC or PPO) and score it on test contexts.", True, "parse_cycles"),
    "main": Command("run_commands", "command_main", "Imitation, the paper's figures, contextual refinement and "
                    "evaluation on test contexts, end to end.", True, "parse_main"),
}
EXTRA_HINT = 'pip install "rdmp-gym[agents]"'


def _usage() -> str:
    lines = [f"usage: rdmp-gym {{{','.join(COMMANDS)}}} [--help] ...  (rdmp-gym {__version__})", ""]
    lines += [f"  {name:9s} {command.about}" for name, command in COMMANDS.items()]
    extra = [name for name, command in COMMANDS.items() if command.needs_extra]
    lines += ["", f"{', '.join(extra)} need the agents extra ({EXTRA_HINT}); fit needs only the core install.",
              "rdmp-gym COMMAND --help lists a command's flags and their defaults."]
    return "\n".join(lines)


def _command(name: str, parse_only: bool = False) -> Callable[[Sequence[str]], Any]:
    """The function of command ``name`` (or its parse-only function); a missing module of an extra is an
    ``ImportError`` naming the extra."""
    command = COMMANDS[name]
    try:
        module = importlib.import_module(f"{__package__}.{command.module}")
    except ModuleNotFoundError as error:
        if error.name and error.name.split(".")[0] in EXTRA_MODULES:
            raise ImportError(f"needs the agents extra (missing module {error.name!r}): {EXTRA_HINT}") from error
        raise
    return getattr(module, command.parser if parse_only else command.function)


def parse(argv: Sequence[str]) -> Any:
    """Parse an ``rdmp-gym`` command line (without the program name, e.g. ``["train", "--out", "runs/x"]``) into
    its command's dataclass, without running it: :class:`~rdmp_gym.agents.run_commands.TrainCommand` (the
    learner's settings as ``options``), ``MainCommand``, ``EvaluateCommand`` or
    :class:`~rdmp_gym.agents.fit_command.FitCommand`. A ``--resume`` line is parsed over the task's defaults
    (no run directory is read).

    Raises:
        SystemExit: from the parser, for an unknown flag or a bad value (code 2) or ``--help`` (code 0).
        ValueError: an unknown command, or values the parser accepts that make no command (no ``--out``).
    """
    argv = list(argv)
    if not argv or argv[0] not in COMMANDS:
        raise ValueError(f"command: expected one of {sorted(COMMANDS)}, got {argv[0] if argv else 'none'!r}")
    return _command(argv[0], parse_only=True)(argv[1:])


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``rdmp-gym``; returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(_usage())
        return 0 if argv else 2
    if argv[0] == "--version":
        print(f"rdmp-gym {__version__}")
        return 0
    name = argv[0]
    if name not in COMMANDS:
        print(f"{_usage()}\nrdmp-gym: error: unknown command {name!r}", file=sys.stderr)
        return 2
    try:
        _command(name)(argv[1:])
    except SystemExit as exit_:                      # tyro's --help (0) and its errors (2)
        return exit_.code if isinstance(exit_.code, int) else 2
    except (ValueError, TypeError, OSError, FloatingPointError, ImportError, WorkerError) as error:
        print(f"rdmp-gym {name}: error: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The table-wiping task: everything the envs know of wiping, in one folder.

- :mod:`~rdmp_gym.envs.tasks.wiping.arena`, :mod:`~rdmp_gym.envs.tasks.wiping.scene`: the arena (the room and the
  cup), the sponge tool and the sensors the task adds to the scene; where they are in the compiled scene, the table
  pose and the cup placed for a context, the dirt grid;
- :mod:`~rdmp_gym.envs.tasks.wiping.context`: the context (patch, table pose, sponge start, the cup), drawn and
  validated, and the observation;
- :mod:`~rdmp_gym.envs.tasks.wiping.approach`, :mod:`~rdmp_gym.envs.tasks.wiping.coverage`: the task's own action
  dimensions (the lifted approach, the covering sweep);
- :mod:`~rdmp_gym.envs.tasks.wiping.simulation`: the wiping task's hook on the simulation core (the wrist-force
  adaptation of the pressing depth, fine physics steps after the first contact, dirt wear, collisions, the cup);
- :mod:`~rdmp_gym.envs.tasks.wiping.force_learning`, :mod:`~rdmp_gym.envs.tasks.wiping.clearance`: the learned
  pressing-depth profile and the cup clearance;
- :mod:`~rdmp_gym.envs.tasks.wiping.reward`, :mod:`~rdmp_gym.envs.tasks.wiping.info`: the reward terms, the success
  criteria's statistics and the info keys;
- :mod:`~rdmp_gym.envs.tasks.wiping.versions`, :mod:`~rdmp_gym.envs.tasks.wiping.settings`: what each version
  changes, the typed settings and the learner defaults;
- :mod:`~rdmp_gym.envs.tasks.wiping.step`: the task's step book, its step interface on the generic step twin (the
  ids ``rdmp_gym/{Armar,Panda}WipeStep-v3``);
- :mod:`~rdmp_gym.envs.tasks.wiping.faces`, :mod:`~rdmp_gym.envs.tasks.wiping.env`: the envs of the ids
  ``rdmp_gym/{Armar,Panda}Wipe{,Step}-v{N}``;
- :mod:`~rdmp_gym.envs.tasks.wiping.legacy`: the published versions 1 and 2, frozen (their description, their step
  env, which runs the DMP online, and the deprecated ``rdmp_gym/ArmarWipe-v0``).

The package imports nothing on its own (the id registry reads its learner defaults without loading MuJoCo).
"""

"""Whole recordings and their fit: rests, an approach, a drifting rhythm, a departure, several sessions, poses.

Built on :mod:`rdmp_gym.dmp` and :mod:`rdmp_gym.signals`:

* :mod:`~rdmp_gym.recordings.recording_fit`: one recording, its slow motion as the anchor's travel, the rhythm with
  a short entry and the ending;
* :mod:`~rdmp_gym.recordings.session_fit`: a recording with several sessions;
* :mod:`~rdmp_gym.recordings.pose_fit`: a recording of a pose (position and orientation);
* :mod:`~rdmp_gym.recordings.pose_io`: pose recordings from CSV files.
"""

"""Many independent targets in one call (:func:`evoik_pin.solve_many`, reachability maps), API above engines.

* :mod:`.api`: :func:`~.api.solve_many` (argument checks, backend choice, the stats);
* :mod:`.threads`: :class:`~.threads.BatchSolver`, the batched rounds on worker threads of this process;
* :mod:`.ray_actors`: the same solver on Ray actors (``backend="ray"``);
* :mod:`.targets` (tip targets) and :mod:`.goal_lists` (goal lists): the call's problems chunk by chunk, in one form
  (:class:`~.goal_lists.GoalBlock`: a tip target is the one-goal problem ``[Pose(tip, T)]``); :mod:`.outcome`: the
  answers as arrays (:class:`~.outcome.BatchOutcome`) and what ``solve_many`` returns
  (:class:`~.outcome.BatchResults`).

Data flows down: ``api`` -> ``ray_actors`` -> ``threads`` -> ``targets``, ``outcome``; nothing below imports
the API.
"""

"""Many independent targets in one call (:func:`evoik_pin.solve_many`, reachability maps), API above engines.

* :mod:`.solve_many_call`: :func:`~.solve_many_call.solve_many` (argument checks, backend choice, the stats);
* :mod:`.threads`: :class:`~.threads.BatchSolver`, the batched rounds on worker threads of this process;
* :mod:`.ray_actors`: the same solver on Ray actors (``backend="ray"``);
* :mod:`.targets` (tip targets) and :mod:`.goal_lists` (goal lists): the call's problems chunk by chunk, in one form
  (:class:`~.goal_lists.GoalBlock`: a tip target is the one-goal problem ``[Pose(tip, T)]``); :mod:`.batch_results`: the
  answers as arrays (:class:`~.batch_results.BatchOutcome`) and what ``solve_many`` returns
  (:class:`~.batch_results.BatchResults`).

Data flows down: ``solve_many_call`` -> ``ray_actors`` -> ``threads`` -> ``targets``, ``batch_results``; nothing
below imports the API.
"""

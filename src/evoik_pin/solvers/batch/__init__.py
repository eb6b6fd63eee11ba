"""Many independent problems in one call (:func:`evoik_pin.solve_many`, reachability maps): :mod:`.solve_many_call`
(the call) over :mod:`.ray_actors` over :mod:`.threads` (the engine) over :mod:`.goal_lists` (the problems, chunk by
chunk) and :mod:`.batch_results` (the answers); nothing below imports the API."""

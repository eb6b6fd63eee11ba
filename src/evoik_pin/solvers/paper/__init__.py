"""The papers' evolutionary and analytic methods (see PAPERS.md), and the population pieces they share.

* :mod:`.common`: initial populations, bound handling, diversity, Halton points and :class:`~.common.SolverRun`
  (time, history, stopping rules, the :class:`~evoik_pin.Result`);
* :mod:`.de_ops`: differential-evolution operators as plain vectorized functions (also memetic's);
* :mod:`.clustering`: wrapped joint-space distances and leader clustering (the all-solutions methods);
* NSGA-II's pieces: :mod:`.pareto_sorting` (constraint domination, non-dominated sorting, crowding, survival,
  tournaments), :mod:`.nsga2_minimizer` (the generic minimizer and its SBX and polynomial mutation),
  :mod:`.task_repair` (damped-least-squares steps towards a tip target);
* the methods, each registered by name on import: :mod:`.de` (``de``), :mod:`.isade` (``isade``), :mod:`.pso`
  (``pso``), :mod:`.mode` (``mode``), :mod:`.ga` (``ga``, ``ga-binary``), :mod:`.hga` (``hga``), :mod:`.nsga2`
  (``nsga2``), :mod:`.analytic` (``algebraic`` and the closed forms).

Nothing here imports the LM engine, the global search or the batch machinery.
"""

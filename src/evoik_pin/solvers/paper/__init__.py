"""The papers' evolutionary and analytic methods (see PAPERS.md), each module registering its methods on import,
and the population pieces they share (:mod:`.common`, :mod:`.de_ops`, :mod:`.clustering`, :mod:`.pareto_sorting`,
:mod:`.nsga2_minimizer`, :mod:`.task_repair`); nothing here imports the LM engine, global search or batch machinery.
"""

"""The papers' evolutionary and analytic methods (see PAPERS.md), each module registering its methods by name on
import, and the population pieces they share (:mod:`.common`, :mod:`.de_ops`, :mod:`.clustering`,
:mod:`.pareto_sorting`, :mod:`.nsga2_minimizer`, :mod:`.task_repair`). Nothing here imports the LM engine, the
global search or the batch machinery.
"""

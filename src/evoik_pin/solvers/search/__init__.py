"""The global solvers built on the LM engine: ``memetic`` (:mod:`.memetic`, its runs :mod:`.memetic_runs`, its
compiled guaranteed runs :mod:`.guaranteed_runs`, an IKSolver's :mod:`.repeat_call`), goal sets and ``prefer``
(:mod:`.answer_choice`, :mod:`.prefer`), ``memetic-all`` (:mod:`.all_solutions`, :mod:`.solution_classes`), the seed
table they start from (:mod:`.seed_table`, :mod:`.nearest`) and a velocity box's solve (:mod:`.velocity_box`).
"""

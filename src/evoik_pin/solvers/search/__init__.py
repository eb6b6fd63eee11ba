"""The global solvers built on the LM engine: the seed table, ``memetic`` and ``memetic-all``.

* :mod:`.seed_table`: configurations spread over a search box with their tip poses, searchable by nearness to a
  target (read by memetic, memetic-all and the batch engine);
* :mod:`.memetic`: ``memetic``, LM from ``q0`` and the seed table, then DE populations polished by LM;
* :mod:`.all_solutions`: ``memetic-all``, every distinct solution of one target;
* :mod:`.solution_classes`: distinct solutions among converged LM runs (classes modulo 2 pi).
"""

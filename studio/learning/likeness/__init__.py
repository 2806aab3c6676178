"""How alike a rollout and a demonstration are: DTW, Frechet, LDLJ, SPARC, the likeness card of any
policy and of a run's demonstrations."""

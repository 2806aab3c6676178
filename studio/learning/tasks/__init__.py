"""The learning tasks: the tabular MDP, the paper's arm grid, the continuous arm reach, their robot,
goal, Gymnasium environments and the demonstrations' paths on them (private modules; the public names
are re-exported by ``studio.learning``)."""

"""Baselines beside Dyna-Q, each a learner like the others: the teacher (the demonstrations
followed, no learning) and behaviour cloning (toward the demonstrated next state of the nearest
demonstrated state)."""

from ._cloning import Cloning as Cloning
from ._cloning import fit_cloning as fit_cloning
from ._learner import CLONING_KIND as CLONING_KIND
from ._learner import TEACHER_KIND as TEACHER_KIND
from ._learner import CloningLearner as CloningLearner
from ._learner import TeacherLearner as TeacherLearner
from ._policy import CloningPolicyFile as CloningPolicyFile
from ._policy import TeacherPolicyFile as TeacherPolicyFile

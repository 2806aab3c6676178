"""The person's arm: the 7-DOF human arm model and its fits to a tape, to pose landmarks and to
a hand pose, filtered and tracked over a stream (the public names are ``studio.kinematics``'s)."""

"""Run folders: a run's request and record, training it in a thread, its curves, notes, owner and
policy summary."""

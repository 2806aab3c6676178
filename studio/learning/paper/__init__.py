"""The paper's experiments (``studio reproduce``) and the measurements beyond it."""

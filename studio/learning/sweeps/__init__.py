"""Sweeps: specs, running their trials on Ray Tune, the sweep folder, its summary and listing."""

"""Task Q1: which object balls does the cue ball touch by the horizon."""

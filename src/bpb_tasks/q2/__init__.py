"""Task Q2: which walls does the cue ball touch by the horizon."""

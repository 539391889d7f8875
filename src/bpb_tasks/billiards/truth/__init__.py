"""The ground truth of a billiards scene: ``outcome`` (what a simulator returns), ``final`` (the
``final.json`` model derived from it) and ``predictors`` (reference predictions)."""

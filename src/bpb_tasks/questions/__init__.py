"""What the billiards questions q1-q3 share: the common prompt, the base class, answer helpers,
the ball-id rule, the label scorer and the confusion diagnostics."""

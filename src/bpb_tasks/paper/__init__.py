"""The paper's suite (0.3 Q1 + 0.3 Q2 + 0.4 Q3) and the stasis index over the three questions."""

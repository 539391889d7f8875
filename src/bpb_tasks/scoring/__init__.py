"""Built-in scorers for Q1, Q2 and Q3 and the paper's total score (SPEC section 8)."""

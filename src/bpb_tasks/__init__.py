"""Built-in tasks (q1, q2, q3), the billiards scene family and the simulators."""

"""Task-motion planning (paper §III-C, GROP): standing positions, feasibility, navigation,
the order of objects, and the plan of highest utility."""

"""The studies: the paper's 10-DOF lumped model (``lumped10``) and the partially
connected double beam (``double_beam``), each a small package; the registry of shipped
cases, the paper's data and synthetic test series."""

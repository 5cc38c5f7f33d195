"""Application layer: the studies (10-DOF lumped model, partially connected double
beam), data readers, modal identification, the estimator, diagnosis and the CLI."""

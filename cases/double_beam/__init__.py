"""The partially connected double beam of the paper's Sec. 4: FE model (model,
calibration), FE-level check (fe_check), the reproduction (settings, joint_setup,
pipeline, weak_joint, study; report, statements, markdown, files) and the Monte Carlo
of its predictions (uncertainty, uncertainty_report)."""

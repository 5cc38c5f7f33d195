"""The partially connected double beam of the paper's Sec. 4: model, calibration, study,
report."""

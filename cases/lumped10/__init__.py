"""The paper's 10-DOF lumped model with two Iwan joints (Sec. 3): model, study, report."""

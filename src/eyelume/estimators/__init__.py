"""Estimators: strategies that turn kernels into pictures."""

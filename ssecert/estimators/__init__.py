"""Estimators: shrinkage operators, static decoders and dynamic observers."""

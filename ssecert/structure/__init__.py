"""Structural analyses: can any estimator succeed, and will Lasso find the attack?"""

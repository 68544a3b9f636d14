"""tightknot.solvers"""

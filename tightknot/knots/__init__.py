"""tightknot.knots"""

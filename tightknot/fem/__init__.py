"""tightknot.fem"""

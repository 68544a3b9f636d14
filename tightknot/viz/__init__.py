"""tightknot.viz"""

"""tightknot.rods"""

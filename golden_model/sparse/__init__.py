"""rasterhw.golden_model.sparse"""

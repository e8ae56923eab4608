"""rasterhw.golden_model.experts"""

"""rasterhw.golden_model.vzbuf"""

"""rasterhw.golden_model"""

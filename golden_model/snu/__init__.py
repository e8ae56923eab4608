"""rasterhw.golden_model.snu"""

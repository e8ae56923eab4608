"""rasterhw.golden_model.zbm"""

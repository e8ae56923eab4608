"""Reports: the row framework, bench, demo page, llvmpipe comparison."""

// placeholder (issue 14 in progress)

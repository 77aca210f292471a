// written in this change

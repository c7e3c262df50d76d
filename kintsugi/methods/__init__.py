"""The methods: each package holds one paradigm with its typed settings, its reasoner roles, its
figures and its tables. A method may run on any task whose robot it drives (its registry tag)."""

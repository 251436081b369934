"""visemeface.render"""

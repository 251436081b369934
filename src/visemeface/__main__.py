from visemeface.cli import main

raise SystemExit(main())

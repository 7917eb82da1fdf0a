from imdrive.cli import main

raise SystemExit(main())
